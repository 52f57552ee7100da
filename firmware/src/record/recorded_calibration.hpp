#pragma once

// The calibration a recording carries (the recording output attaches the rig's to each file), so
// that a recording replayed as a scene is rectified as it was recorded.
#include <filesystem>
#include <optional>
#include <string_view>

#include "epipole/calib/calibration.hpp"

namespace epipole::firmware::record {

// The attachment's name, in the board's calibration format (calib::format_calibration).
inline constexpr std::string_view kCalibrationAttachment = "calibration.yaml";

// The recording's calibration; none when it was recorded without one. Throws Error naming the
// file when it is not a recording or its calibration does not read.
std::optional<calib::StereoCalibration> recorded_calibration(const std::filesystem::path& file);

}  // namespace epipole::firmware::record
