#pragma once

// The disparity filters' kernel interfaces: the scalar *_ref that defines each result and its SIMD
// variants. Internal to vision: its sources and the tests that check every path against the
// reference (target epipole_vision_kernels) include it.
#include <cstddef>
#include <cstdint>

namespace epipole::vision::kernels {

using FillHolesRow = void(std::int16_t* row, int width, int max_hole);
void fill_holes_row_ref(std::int16_t* row, int width, int max_hole);
void fill_holes_row_neon(std::int16_t* row, int width, int max_hole);

// `now` becomes the filtered row, and `last` the same.
using TemporalRow = void(std::int16_t* now, std::int16_t* last, int width, int weight,
                         int max_step_x16);
void temporal_row_ref(std::int16_t* now, std::int16_t* last, int width, int weight,
                      int max_step_x16);
void temporal_row_neon(std::int16_t* now, std::int16_t* last, int width, int weight,
                       int max_step_x16);

// One pass of the spatial filter over a whole image: along every row both ways, then along every
// column both ways. scratch: 9 x width elements (the reference needs none).
using SpatialPass = void(std::int16_t* image, std::ptrdiff_t stride, int width, int height,
                         int weight, int max_step_x16, std::int16_t* scratch);
void spatial_pass_ref(std::int16_t* image, std::ptrdiff_t stride, int width, int height, int weight,
                      int max_step_x16, std::int16_t* scratch);
void spatial_pass_neon(std::int16_t* image, std::ptrdiff_t stride, int width, int height,
                       int weight, int max_step_x16, std::int16_t* scratch);

}  // namespace epipole::vision::kernels
