#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "epipole/core/image.hpp"
#include "epipole/hal/camera.hpp"
#include "epipole/hal/clock.hpp"
#include "epipole/hal/registry.hpp"
#include "epipole/hal/serial_port.hpp"
#include "epipole/hal/side.hpp"
#include "epipole/hal/trigger.hpp"

namespace epipole::hal {

struct SimBoard;

// What the simulated board needs besides its parts' configurations. Read only when the cameras'
// backend is simulated (BackendTraits::simulated).
struct SimSettings {
  std::vector<GrayImage> left, right;  // the scene (frame n shows image n % count)
  std::uint64_t seed = 7;              // camera jitter and the random faults
  double drop_rate = 0;                // per frame and camera, independent per side
  double corrupt_rate = 0;
  bool charge_compute = false;  // the frame loop's work takes virtual time (Clock::spend)
};

// A board's parts: a backend name and its configuration for each (kNoBackend: not there).
struct HardwareConfig {
  std::string camera_backend;
  CameraConfig left, right;
  std::string trigger_backend{kNoBackend};
  TriggerConfig trigger;
  std::string serial_backend{kNoBackend};
  SerialConfig serial;
  SimSettings sim;
};

// A board's devices made through a registry, and the clock they run on: the simulated board's
// virtual clock when its cameras are simulated, else the monotonic clock. The simulation (its
// clock, trigger master, scene and random faults) lives in here: callers see cameras, a trigger
// line, a serial port and a clock, whatever the board. Construction throws Error naming the
// part that cannot be made; a device that is not there yet is no error (the backends wait).
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
  // The simulated scene's images and the memory they hold (both 0 on hardware).
  std::size_t scene_images() const;
  std::size_t scene_bytes() const;
  // The simulated board, for tests that inject faults (hal/src/sim/sim.hpp); null on hardware.
  SimBoard* sim() const { return sim_.get(); }

 private:
  std::unique_ptr<SimBoard> sim_;
  MonotonicClock monotonic_;
  Clock* clock_ = &monotonic_;
  std::array<std::unique_ptr<CameraSource>, 2> cameras_;
  std::unique_ptr<TriggerLine> trigger_;
  std::unique_ptr<SerialPort> serial_;
};

}  // namespace epipole::hal
