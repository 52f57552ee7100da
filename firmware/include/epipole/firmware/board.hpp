#pragma once

#include <memory>
#include <string>
#include <vector>

#include "epipole/firmware/board_config.hpp"
#include "epipole/hal/camera.hpp"
#include "epipole/hal/clock.hpp"
#include "epipole/hal/hardware.hpp"
#include "epipole/hal/recovery.hpp"
#include "epipole/hal/serial_port.hpp"
#include "epipole/hal/stereo_pairing.hpp"
#include "epipole/hal/trigger.hpp"

namespace epipole::firmware {

// The hardware of a board — cameras, trigger line, serial link, clock — made from its
// configuration by the HAL (hal::Hardware, through the backend registry), each camera and the
// link wrapped so that they recover from faults by themselves (hal/recovery.hpp). Everything runs
// on the hardware's clock.
class Board {
 public:
  explicit Board(const BoardConfig& config);
  // These parts instead of the configuration's (hardware_config() changed: stand-ins).
  explicit Board(hal::HardwareConfig hardware);
  ~Board();
  Board(const Board&) = delete;
  Board& operator=(const Board&) = delete;

  hal::Clock& clock() { return hardware_.clock(); }
  hal::CameraSource& left() { return left_; }
  hal::CameraSource& right() { return right_; }
  hal::RecoveringCamera& left_recovery() { return left_; }
  hal::RecoveringCamera& right_recovery() { return right_; }
  const hal::RecoveringCamera& left_recovery() const { return left_; }
  const hal::RecoveringCamera& right_recovery() const { return right_; }
  hal::TriggerLine* trigger() { return hardware_.trigger(); }
  // Null when the board has no link.
  hal::SerialPort* serial() { return serial_ ? serial_.get() : nullptr; }
  const hal::RecoveringSerialPort* serial_recovery() const { return serial_.get(); }
  // The robot's end of a link the board makes itself (a pseudo-terminal), else empty.
  std::string serial_peer() const;
  // The devices themselves, unwrapped.
  hal::Hardware& hardware() { return hardware_; }
  const hal::Hardware& hardware() const { return hardware_; }

 private:
  hal::Hardware hardware_;
  hal::RecoveringCamera left_, right_;
  std::unique_ptr<hal::RecoveringSerialPort> serial_;
};

// The HAL's configuration of a board's parts.
hal::HardwareConfig hardware_config(const BoardConfig& config);

}  // namespace epipole::firmware
