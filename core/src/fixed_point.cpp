#include "epipole/core/fixed_point.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace epipole {

int to_fixed_point(float v, std::int16_t* integer) {
  constexpr auto kMin = std::numeric_limits<std::int32_t>::min();
  constexpr auto kMax = std::numeric_limits<std::int32_t>::max();
  std::int32_t fixed = kMin;
  if (!std::isnan(v)) {
    const double scaled = static_cast<double>(v) * kMapFractionSteps;  // exact
    if (scaled >= static_cast<double>(kMax)) {
      fixed = kMax;
    } else if (scaled <= static_cast<double>(kMin)) {
      fixed = kMin;
    } else {
      // Round half to even without depending on the floating-point rounding mode.
      const double below = std::floor(scaled);
      auto rounded = static_cast<std::int64_t>(below);
      const double rest = scaled - below;
      if (rest > 0.5 || (rest == 0.5 && (rounded & 1) != 0)) ++rounded;
      fixed = static_cast<std::int32_t>(std::clamp<std::int64_t>(rounded, kMin, kMax));
    }
  }
  const std::int32_t whole = fixed >> kMapFractionBits;  // arithmetic shift: floor
  *integer = static_cast<std::int16_t>(std::clamp<std::int32_t>(
      whole, std::numeric_limits<std::int16_t>::min(), std::numeric_limits<std::int16_t>::max()));
  return static_cast<int>(fixed & (kMapFractionSteps - 1));
}

}  // namespace epipole
