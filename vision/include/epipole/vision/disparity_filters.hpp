#pragma once

// Post-filters of a dense disparity map (x16, invalid below 0: stereo.hpp), in place and without
// memory of their own. Each has a scalar reference that defines its result and a NEON version
// that gives the same bits.
#include <cstdint>

#include "epipole/core/image.hpp"
#include "epipole/core/simd.hpp"

namespace epipole::vision {

// Fills each run of invalid pixels along a row that has valid pixels on both sides and is at
// most `max_hole` pixels long with the farther of the two (the smaller disparity): a hole beside
// a near object is mostly the background it hides from the other camera (an occlusion), or a
// surface too plain to match between two of its own pixels. Runs that touch the image's border
// have one side only, and are left as they are. max_hole 0 changes nothing.
void fill_holes(ImageView<std::int16_t> disparity, int max_hole, SimdPath path);

namespace kernels {
using FillHolesRow = void(std::int16_t* row, int width, int max_hole);
void fill_holes_row_ref(std::int16_t* row, int width, int max_hole);
void fill_holes_row_neon(std::int16_t* row, int width, int max_hole);
}  // namespace kernels

}  // namespace epipole::vision
