#pragma once

#include <functional>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "epipole/hal/backend_settings.hpp"
#include "epipole/hal/camera.hpp"
#include "epipole/hal/clock.hpp"
#include "epipole/hal/serial_port.hpp"
#include "epipole/hal/trigger.hpp"

namespace YAML {
class Node;
}

namespace epipole::yaml {
class Fields;
}

namespace epipole::hal {

struct HardwareConfig;

// What a backend may need besides its configuration.
struct BackendContext {
  Clock* clock = nullptr;         // the board's clock (MonotonicClock on hardware)
  BackendBoard* board = nullptr;  // what the devices of this backend share, if any
};

// The board file's word for a part the board does not have (no trigger line: free-running
// cameras; no serial link). Not a backend: nothing is made for it.
inline constexpr std::string_view kNoBackend = "none";

// What a backend is, besides its name: callers ask this instead of comparing names.
struct BackendTraits {
  bool simulated = false;     // part of the simulated board (its virtual clock and scenes)
  bool needs_device = false;  // its configuration must name a device node
  // The board file's section its devices share (a SectionBackend's name); null: none.
  const char* section = nullptr;
};

// A backend's own section of the board file (the simulated board's `sim:`): read when the
// board file is loaded, made into what its devices share when the board's hardware is.
struct SectionBackend {
  std::string name;  // the board file's top-level key
  // Reads the section (an undefined node when the file has none), with the options given for it;
  // every error names the file and the key (yaml::Fields).
  std::function<std::unique_ptr<BackendSettings>(
      const YAML::Node& section, const yaml::Fields& file, std::span<const BackendOption> options)>
      read;
  // What the board's devices share, made before them; throws Error naming what is wrong.
  std::function<std::unique_ptr<BackendBoard>(const BackendSettings& settings,
                                              const HardwareConfig& board)>
      make_board;
  // Changes a board's configuration so that this backend's devices stand in for its own, of
  // the same size, opening nothing (start-up checks without the devices); empty: it cannot.
  std::function<void(HardwareConfig& board)> stand_in;
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
  void add_section(SectionBackend section);

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
  // The backend sections, in the order they were added; section(): null for a name of none.
  const std::vector<SectionBackend>& sections() const { return sections_; }
  const SectionBackend* section(std::string_view name) const;

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
  std::vector<SectionBackend> sections_;
};

}  // namespace epipole::hal
