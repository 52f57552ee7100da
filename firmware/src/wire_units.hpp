#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "epipole/hal/clock.hpp"

namespace epipole::firmware::detail {

// A count or size in a message field too narrow for it: the field's largest value.
template <typename T>
T saturate(std::uint64_t value) {
  return static_cast<T>(std::min<std::uint64_t>(value, std::numeric_limits<T>::max()));
}

// Nanoseconds as a message's microseconds: never negative, saturating.
inline std::uint32_t to_us(hal::Nanoseconds ns) {
  return saturate<std::uint32_t>(static_cast<std::uint64_t>(std::max<hal::Nanoseconds>(ns, 0)) /
                                 1000);
}

// `value` in units of `unit`, rounded and saturated to T's range (NaN: 0).
template <typename T>
T in_units(double value, double unit) {
  const double v = value / unit;
  if (std::isnan(v)) return T{0};
  return static_cast<T>(std::llround(
      std::clamp(v, double{std::numeric_limits<T>::min()}, double{std::numeric_limits<T>::max()})));
}

}  // namespace epipole::firmware::detail
