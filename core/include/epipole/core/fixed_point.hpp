#pragma once

#include <cstdint>

namespace epipole {

// Sub-pixel source coordinates of the rectification maps: 5 fractional bits (1/32 pixel), the
// format of OpenCV's CV_16SC2 + CV_16UC1 maps. Shared by the map builder (calib) and the remap
// stage (vision) so that both round identically.
inline constexpr int kMapFractionBits = 5;
inline constexpr int kMapFractionSteps = 1 << kMapFractionBits;  // 32

// One coordinate to fixed point as cv::convertMaps does: v * 32 rounded to the nearest integer,
// ties to even (cvRound), saturated to int32 (NaN: INT32_MIN); the low 5 bits are returned (the
// fraction, 0..31) and the rest, saturated to int16, goes to *integer (the floor of v, for
// coordinates an int16 can hold).
int to_fixed_point(float v, std::int16_t* integer);

}  // namespace epipole
