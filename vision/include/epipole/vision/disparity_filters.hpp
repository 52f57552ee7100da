#pragma once

// Post-filters of a dense disparity map (x16, invalid below 0: stereo.hpp), in place. Each has
// a scalar reference that defines its result and a NEON version that gives the same bits.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "epipole/core/image.hpp"
#include "epipole/core/simd.hpp"

namespace epipole::vision {

// Fills each run of invalid pixels along a row that has valid pixels on both sides and is at
// most `max_hole` pixels long with the farther of the two (the smaller disparity): a hole beside
// a near object is mostly the background it hides from the other camera (an occlusion), or a
// surface too plain to match between two of its own pixels. Runs that touch the image's border
// have one side only, and are left as they are. max_hole 0 changes nothing.
void fill_holes(ImageView<std::int16_t> disparity, int max_hole, SimdPath path);

// Smooths the disparity over time: where a pixel is valid in this pair and in the filter's last
// result, and the two differ by at most `max_step` pixels, it becomes
//   last + sign(d) * ((|d| * weight + 128) >> 8)   (x16 values, d = now - last;
//                                                   weight = new_percent * 256 / 100)
// and keeps its value otherwise (a step larger than max_step is motion or a new surface, taken
// at once; an invalid pixel stays invalid: old depth is never shown where there is none now).
// The result is the filter's memory for the next pair: one disparity image, allocated here.
class TemporalFilter {
 public:
  // new_percent: the new pair's weight, 1..99; max_step: 1..7 px. Throws Error otherwise or for
  // an empty size.
  TemporalFilter(int width, int height, int new_percent, int max_step);

  void apply(ImageView<std::int16_t> disparity, SimdPath path);
  // Forgets the past (the next pair passes unchanged): after a gap, a camera reopened.
  void reset();

  std::size_t working_set_bytes() const { return last_.size_bytes(); }

 private:
  Image<std::int16_t> last_;
  int weight_;    // x/256
  int max_step_;  // x16
};

// Smooths the disparity within each surface and keeps its edges: a recursive filter along each
// row (left to right, then right to left), then along each column (down, then up), `passes`
// times, as the spatial filter of Intel RealSense and Luxonis DepthAI. Each pixel valid beside
// the one filtered before it on its way, and within `max_step` px of it, becomes
//   before + sign(d) * ((|d| * weight + 128) >> 8)   (x16 values, d = pixel - before;
//                                                     weight = own_percent * 256 / 100)
// the same blend as the temporal filter's; a larger step is an edge and stops the smoothing,
// and so does an invalid pixel (it stays invalid: nothing is filled). Memory: nine rows of the
// disparity's width, allocated here (the NEON path turns bands of eight rows into columns).
class SpatialFilter {
 public:
  // own_percent: a pixel's weight against the one before it, 1..99; max_step: 1..7 px;
  // passes: 1..4. Throws Error otherwise or for an empty size.
  SpatialFilter(int width, int height, int own_percent, int max_step, int passes);

  void apply(ImageView<std::int16_t> disparity, SimdPath path);

  std::size_t working_set_bytes() const { return scratch_.size() * sizeof(std::int16_t); }

 private:
  int width_, height_;
  int weight_;    // x/256
  int max_step_;  // x16
  int passes_;
  std::vector<std::int16_t> scratch_;
};

}  // namespace epipole::vision
