#pragma once

// A scene of board/sim (the simulated board the project ships): its configuration with some keys
// set, its rig's calibration and its pairs.
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "epipole/calib/calibration.hpp"
#include "epipole/firmware/board_config.hpp"
#include "epipole/firmware/firmware.hpp"
#include "sim/sim_settings.hpp"
#include "test_paths.hpp"

namespace epipole::test {

struct BoardScene {
  firmware::BoardConfig config;
  std::optional<calib::StereoCalibration> rig;
  hal::StereoImages images;
};

// Scene `name` chosen, `overrides` (KEY=VALUE) set; its pairs loaded when `images`.
inline BoardScene board_scene(const std::string& name, const std::vector<std::string>& overrides,
                              bool images = true) {
  const hal::BackendOption option{"scene", name};
  BoardScene s{firmware::load_board_config(std::filesystem::path(source_dir()) / "board" / "sim",
                                           overrides, std::span(&option, 1)),
               {},
               {}};
  s.rig = firmware::load_board_calibration(s.config);
  if (images) {
    s.images = hal::load_scene(hal::sim_settings(s.config.sections).chosen(), s.config.width(),
                               s.config.height());
  }
  return s;
}

}  // namespace epipole::test
