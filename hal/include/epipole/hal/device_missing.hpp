#pragma once

// A device that is not there (yet): a camera or serial adapter that appears after the firmware
// started (a slow USB device at boot), or one unplugged. Unlike other Errors it is no mistake in
// the configuration: the recovering wrappers (recovery.hpp) wait for it with back-off.
#include "epipole/core/error.hpp"

namespace epipole::hal {

class DeviceMissing : public Error {
 public:
  using Error::Error;
};

}  // namespace epipole::hal
