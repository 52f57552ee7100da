#pragma once

// Rectified stereo pairs with exact ground truth, rendered from the data sets' real textures: a
// test fixture (deterministic: the same pixels on every run and machine). A scene is a few
// planar surfaces, each with a texture and a disparity a*x + b*y + c in the left view over a
// rectangle of it. Both views are rendered by finding, for each pixel, the nearest surface
// (the largest disparity) that covers it and sampling its texture at the surface point (the left
// view's x, y: a point looks the same in both views up to the interpolation); the ground truth
// is the left view's disparity, and a left pixel is occluded where another surface covers its
// point in the right view, or where the point falls outside it. Then what cameras add: the
// right view 8 % darker and 6 levels brighter at black, and up to 3 levels of noise per pixel.
#include <string>
#include <vector>

#include "epipole/core/image.hpp"

namespace epipole::test {

struct SyntheticPair {
  std::string name;
  GrayImage left, right;
  Image<float> truth;     // the left view's disparity, pixels (every pixel known)
  GrayImage nonoccluded;  // Middlebury's convention: 255 seen in both views, 128 occluded
};

// The scenes: "fronto" (one fronto-parallel plane at a fractional disparity), "slanted" (one
// plane slanted both ways), "boxes" (three near boxes over a far wall: occlusions), "low-texture"
// (a wide box of a real texture at 1/16 of its contrast on a textured wall), "thin" (bars and
// wires 2 to 4 px wide in front of a wall). Textures: scripts/fetch-data.sh's samples.
std::vector<std::string> synthetic_scene_names();
// Throws Error for an unknown name, or a texture missing from the data sets. `noise_seed`: the
// cameras' noise (another seed: the same scene in another pair of frames).
SyntheticPair synthetic_scene(const std::string& name, int width, int height,
                              unsigned noise_seed = 2024);

}  // namespace epipole::test
