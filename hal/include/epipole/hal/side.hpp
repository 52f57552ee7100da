#pragma once

namespace epipole::hal {

// The two cameras of the rig.
enum class Side { left, right };

// Where a side's entry is in a per-side array: left first.
constexpr int index(Side side) {
  return side == Side::left ? 0 : 1;
}

}  // namespace epipole::hal
