#pragma once

#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "epipole/hal/camera.hpp"
#include "epipole/hal/clock.hpp"
#include "epipole/hal/serial_port.hpp"
#include "epipole/hal/trigger.hpp"

namespace epipole::hal {

struct SimBoard;

// What a backend may need besides its configuration.
struct BackendContext {
  Clock* clock = nullptr;   // the board's clock (MonotonicClock on hardware)
  SimBoard* sim = nullptr;  // the simulated board, for the "sim" backends
};

// The board file's word for a part the board does not have (no trigger line: free-running
// cameras; no serial link). Not a backend: nothing is made for it.
inline constexpr std::string_view kNoBackend = "none";

// What a backend is, besides its name: callers ask this instead of comparing names.
struct BackendTraits {
  bool simulated = false;     // part of the simulated board (its virtual clock and scenes)
  bool needs_device = false;  // its configuration must name a device node
};

using CameraFactory =
    std::function<std::unique_ptr<CameraSource>(const CameraConfig&, const BackendContext&)>;
using TriggerFactory =
    std::function<std::unique_ptr<TriggerLine>(const TriggerConfig&, const BackendContext&)>;
using SerialFactory =
    std::function<std::unique_ptr<SerialPort>(const SerialConfig&, const BackendContext&)>;

// Backends by name, chosen at run time from the board configuration. A backend that is known but
// not built into this binary is registered with the reason instead of a factory. Errors:
// unknown names list the known ones; unavailable backends say why.
class BackendRegistry {
 public:
  void add_camera(std::string name, CameraFactory factory, BackendTraits traits = {});
  void add_trigger(std::string name, TriggerFactory factory, BackendTraits traits = {});
  void add_serial(std::string name, SerialFactory factory, BackendTraits traits = {});
  void add_unavailable_camera(std::string name, std::string reason, BackendTraits traits = {});
  void add_unavailable_trigger(std::string name, std::string reason, BackendTraits traits = {});

  std::unique_ptr<CameraSource> create_camera(std::string_view backend, const CameraConfig& config,
                                              const BackendContext& context = {}) const;
  std::unique_ptr<TriggerLine> create_trigger(std::string_view backend, const TriggerConfig& config,
                                              const BackendContext& context = {}) const;
  std::unique_ptr<SerialPort> create_serial(std::string_view backend, const SerialConfig& config,
                                            const BackendContext& context = {}) const;

  std::vector<std::string> camera_backends() const;
  std::vector<std::string> trigger_backends() const;
  std::vector<std::string> serial_backends() const;
  // A backend's traits; those of no backend (an unknown name, kNoBackend) are all false.
  BackendTraits camera_traits(std::string_view backend) const;
  BackendTraits trigger_traits(std::string_view backend) const;
  BackendTraits serial_traits(std::string_view backend) const;

  // The backends built into this binary: cameras "sim", "v4l2", "libcamera"; triggers "sim",
  // "gpiod"; serial "termios", "pty" (a pseudo-terminal: the simulated board's link).
  static const BackendRegistry& builtin();

 private:
  template <typename Factory>
  struct Entry {
    std::string name;
    Factory factory;
    std::string unavailable;  // non-empty: not built, and why
    BackendTraits traits;
  };
  std::vector<Entry<CameraFactory>> cameras_;
  std::vector<Entry<TriggerFactory>> triggers_;
  std::vector<Entry<SerialFactory>> serials_;
};

}  // namespace epipole::hal
