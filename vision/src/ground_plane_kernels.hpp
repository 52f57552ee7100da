#pragma once

// The ground finder's kernel interface: the scalar *_ref that defines the v-disparity and its
// NEON variant. Internal to vision: its sources and the tests that check every path against the
// reference (target epipole_vision_kernels) include it.
#include <cstdint>

namespace epipole::vision::kernels {

// The partial histograms a v-disparity row kernel may use: kVDisparityLanes x bins counts.
inline constexpr int kVDisparityLanes = 4;

// One row of the v-disparity: counts[d] (d < bins) becomes the number of the row's pixels
// whose integer disparity, value / 16 rounded down, is d, for d in 1 .. bins - 1; counts[0]
// becomes 0 (no disparity, or invalid: value below 16). bins <= 4096, width <= 65535.
// `scratch`: kVDisparityLanes x bins counts the kernel may overwrite.
using VDisparityRow = void(const std::int16_t* row, int width, int bins, std::uint16_t* counts,
                           std::uint16_t* scratch);
void v_disparity_row_ref(const std::int16_t* row, int width, int bins, std::uint16_t* counts,
                         std::uint16_t* scratch);
void v_disparity_row_neon(const std::int16_t* row, int width, int bins, std::uint16_t* counts,
                          std::uint16_t* scratch);

}  // namespace epipole::vision::kernels
