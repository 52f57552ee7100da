#pragma once

#include <cstddef>
#include <cstdint>

namespace epipole::vision::kernels {

// The reference segment test and score for columns [x_begin, x_end) of one row; writes only
// those scores (leaving 0 untouched elsewhere is the caller's job). Returns the corner count.
int fast_columns_ref(const std::uint8_t* row, const std::ptrdiff_t* circle, int x_begin, int x_end,
                     int threshold, std::uint8_t* scores, int* columns);

}  // namespace epipole::vision::kernels
