#pragma once

#include <cstddef>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "epipole/core/settings_sections.hpp"
#include "epipole/hal/clock.hpp"

namespace epipole::hal {

// A backend's own section of the board file, as the backend read it (the registry's
// SectionBackend::read); opaque to everyone else, who only copies it and hands it back.
class BackendSettings {
 public:
  virtual ~BackendSettings() = default;
  virtual std::unique_ptr<BackendSettings> clone() const = 0;
  // The rig's calibration file the settings name (a simulated scene's own), which overrides the
  // board's; empty: none.
  virtual std::filesystem::path calibration() const { return {}; }
};

// The board file's backend sections by name; a copy copies the settings.
using BackendSections = SettingsSections<BackendSettings>;

// A setting given for a backend's section besides the board file (epipole-fw --scene NAME):
// the backend checks it like the file's keys.
struct BackendOption {
  std::string key;
  std::string value;
};

// What a backend's devices share on one board, made from its section before them (the
// simulated board: its virtual clock, trigger master and scene).
class BackendBoard {
 public:
  virtual ~BackendBoard() = default;
  // The clock the board runs on when it is not the monotonic clock.
  virtual Clock* own_clock() { return nullptr; }
  // The memory it holds for its devices (a simulated scene's images).
  virtual std::size_t memory_bytes() const { return 0; }
};

}  // namespace epipole::hal
