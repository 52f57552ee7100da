#pragma once

#include <cstddef>
#include <span>

#include "epipole/calib/triangulation.hpp"
#include "epipole/vision/sparse_stereo.hpp"

namespace epipole::firmware {

// A sparse match triangulated with Q: the left image position, the right one, the disparity
// and the 3-D point in the rectified left camera's frame (units of the calibration's T).
struct SparsePoint {
  float xl = 0, yl = 0;
  float xr = 0, yr = 0;
  float disparity = 0;
  float x = 0, y = 0, z = 0;
  int distance = 0;       // the match's descriptor distance: smaller is more distinctive
  int left_feature = -1;  // the match's left corner (vision::SparseMatch::left_feature)
};

// The 3-D points of sparse matches (calib::Triangulator::point at (xl, yl) with the match's
// disparity), in the matches' order; a match without a point (a disparity that gives W <= 0)
// is skipped. Writes at most out.size() points and returns how many; `truncated`, when given,
// says whether matches with points were left over. Never allocates (the frame loop calls it).
std::size_t triangulate_matches(const calib::Triangulator& triangulator,
                                std::span<const vision::SparseMatch> matches,
                                std::span<SparsePoint> out, bool* truncated = nullptr);

}  // namespace epipole::firmware
