#pragma once

// Degrees and radians: board files and messages speak degrees, the maths radians.
#include <numbers>

namespace epipole {

constexpr double radians(double degrees) {
  return degrees * std::numbers::pi / 180;
}
constexpr double degrees(double radians) {
  return radians * 180 / std::numbers::pi;
}

}  // namespace epipole
