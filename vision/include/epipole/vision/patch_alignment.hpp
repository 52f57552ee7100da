#pragma once

#include "epipole/core/image.hpp"

namespace epipole::vision {

// Where a patch of one image lies in another, to a fraction of a pixel: the calibration health's
// vertical offsets of matches (docs/calibration.md), which whole-pixel corners cannot give.
struct PatchOffset {
  float dx = 0, dy = 0;  // the right position less the left: (xr - xl, yr - yl)
  float ncc = 0;         // normalised cross-correlation of the patches there
  bool found = false;
};

struct PatchAlignmentConfig {
  int radius = 5;          // the patch: (2 radius + 1)^2 pixels, 1..7
  int iterations = 20;     // at most
  float max_travel = 1.5;  // pixels from the start: further is another patch, not found
  float min_ncc = 0.8f;    // the patches must look alike there
  // The weaker direction's mean squared gradient (grey levels^2 / pixel^2): a patch of one edge
  // cannot say where it lies along the edge.
  float min_gradient = 4;
};

// Lucas-Kanade alignment of a translation (inverse compositional): the left patch centred on
// (xl, yl) found in `right` near (xr, yr), each patch normalised to zero mean and unit variance
// (the cameras' gain and offset differ), the right image sampled bilinearly. Not found when the
// left patch is flat or one edge, when either patch leaves its image, when it does not
// converge, travels further than max_travel or correlates less than min_ncc. Allocates
// nothing.
PatchOffset align_patch(GrayView left, int xl, int yl, GrayView right, float xr, float yr,
                        const PatchAlignmentConfig& config = {});

}  // namespace epipole::vision
