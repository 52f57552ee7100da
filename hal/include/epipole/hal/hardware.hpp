#pragma once

#include <array>
#include <cstddef>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "epipole/hal/camera.hpp"
#include "epipole/hal/clock.hpp"
#include "epipole/hal/registry.hpp"
#include "epipole/hal/serial_port.hpp"
#include "epipole/hal/side.hpp"
#include "epipole/hal/trigger.hpp"

namespace epipole::hal {

// A board's parts: a backend name and its configuration for each (kNoBackend: not there).
struct HardwareConfig {
  std::string camera_backend;
  CameraConfig left, right;
  std::string trigger_backend{kNoBackend};
  TriggerConfig trigger;
  std::string serial_backend{kNoBackend};
  SerialConfig serial;
  int width = 0, height = 0;  // the cameras' image size
  BackendSections sections;   // the board file's backend sections (the registry's)
};

// A board's devices made through a registry, and the clock they run on: the monotonic clock, or
// the one of what the cameras' backend shares (the simulated board's virtual clock, made from
// its section of the board file). Each device gets what its own backend's section makes (one
// per section: devices of backends that share a section share it). Callers see cameras, a trigger
// line, a serial port and a clock, whatever the board. Construction throws Error naming the part
// that cannot be made; a device that is not there yet is no error (the backends wait).
class Hardware {
 public:
  explicit Hardware(HardwareConfig config,
                    const BackendRegistry& registry = BackendRegistry::builtin());
  ~Hardware();
  Hardware(const Hardware&) = delete;
  Hardware& operator=(const Hardware&) = delete;

  Clock& clock() { return *clock_; }
  CameraSource& camera(Side side) { return *cameras_[index(side)]; }
  TriggerLine* trigger() { return trigger_.get(); }  // null: the board has none
  SerialPort* serial() { return serial_.get(); }     // null: the board has no link
  const SerialPort* serial() const { return serial_.get(); }
  // What the cameras' backend shares (null: nothing).
  BackendBoard* backend_board() const { return cameras_board_; }
  // The memory held by what the board's backends share.
  std::size_t backend_bytes() const;

 private:
  void require_cameras_clock(const char* part, const std::string& backend,
                             BackendBoard* board) const;

  // What each backend with a section shares, by section (the cameras' first), and theirs.
  std::vector<std::pair<std::string, std::unique_ptr<BackendBoard>>> boards_;
  BackendBoard* cameras_board_ = nullptr;
  MonotonicClock monotonic_;
  Clock* clock_ = &monotonic_;
  std::array<std::unique_ptr<CameraSource>, 2> cameras_;
  std::unique_ptr<TriggerLine> trigger_;
  std::unique_ptr<SerialPort> serial_;
};

// Replaces the board's cameras and trigger by a backend's stand-ins of the same size that open
// nothing (SectionBackend::stand_in), to size the firmware without its devices; false when they
// need none (the board's cameras open nothing themselves: the simulated board's).
bool stand_in_for_devices(HardwareConfig& config,
                          const BackendRegistry& registry = BackendRegistry::builtin());

}  // namespace epipole::hal
