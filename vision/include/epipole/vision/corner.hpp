#pragma once

namespace epipole::vision {

// A corner at integer pixel coordinates with the detector's strength. For FAST the score is
// OpenCV's FAST score (the largest threshold at which the pixel is still a corner).
struct Corner {
  int x = 0;
  int y = 0;
  float score = 0.0f;
  friend bool operator==(const Corner&, const Corner&) = default;
};

}  // namespace epipole::vision
