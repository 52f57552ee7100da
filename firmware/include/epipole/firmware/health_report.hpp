#pragma once

// What the outputs are offered once a second: the health message, and the calibration's health
// after it when the sparse stage has measured the rig (the same two messages the serial link
// sends).
#include <optional>

#include "epipole/firmware/protocol/messages.hpp"

namespace epipole::firmware {

struct HealthReport {
  protocol::Health health;
  std::optional<protocol::CalibrationHealth> calibration;
};

}  // namespace epipole::firmware
