#pragma once

// The speckle filter of a dense disparity map (x16, invalid below 0: stereo.hpp), in place:
// connected regions of fewer than `min_size` pixels become kInvalidDisparity. Two pixels are
// connected when they are 4-neighbours, both valid, and at most `range` pixels apart in
// disparity (OpenCV's filterSpeckles with maxSpeckleSize = min_size - 1 and maxDiff = range x16,
// where every negative value counts as its newVal). Other invalid values (the left-right
// check's occlusion marks) are kept.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "epipole/core/image.hpp"
#include "epipole/core/simd.hpp"

namespace epipole::vision {

class SpeckleFilter {
 public:
  // min_size >= 1 (1 removes nothing), range 0..255 px. Throws Error otherwise or for an empty
  // size. All memory is allocated here.
  SpeckleFilter(int width, int height, int min_size, int range);

  void apply(ImageView<std::int16_t> disparity, SimdPath path);

  std::size_t working_set_bytes() const;

 private:
  // The runs of one row: begin and end (exclusive) of each, in order.
  struct Runs {
    std::vector<std::int32_t> begin, end;
    int count = 0;
  };
  void find_runs(Runs& runs) const;

  int width_, height_;
  int min_size_;
  int range_x16_ = 0;
  int words_;  // of each mask row
  // Union-find over all runs of the image: a root holds minus its region's size, another run
  // its parent.
  std::vector<std::int32_t> nodes_;
  std::vector<std::uint64_t> valid_, left_, up_;  // one row's masks (speckle_filter_kernels.hpp)
  Runs runs_[2];                                  // the row's runs and the row above's
};

}  // namespace epipole::vision
