#pragma once

// What the calibration fuzzers require of an accepted calibration: it is valid, and Epipole's own
// file of it reads back as the same text.
#include <cstdlib>
#include <string>

#include "epipole/calib/calibration.hpp"

namespace epipole::fuzz {

inline void check_round_trip(const calib::StereoCalibration& calibration) {
  calib::validate(calibration);
  const std::string text = calib::format_calibration(calibration);
  if (calib::format_calibration(calib::parse_calibration(text, "again.yaml")) != text) {
    std::abort();
  }
}

}  // namespace epipole::fuzz
