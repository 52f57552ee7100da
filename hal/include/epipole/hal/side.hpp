#pragma once

namespace epipole::hal {

// The two cameras of the rig.
enum class Side { left, right };

}  // namespace epipole::hal
