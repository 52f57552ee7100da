#include "epipole/firmware/board.hpp"

#include <utility>

namespace epipole::firmware {

hal::HardwareConfig hardware_config(const BoardConfig& config) {
  hal::HardwareConfig h;
  h.camera_backend = config.cameras.backend;
  h.left = config.cameras.left;
  h.right = config.cameras.right;
  h.trigger_backend = config.trigger.backend;
  h.trigger = config.trigger.line;
  h.serial_backend = config.serial.backend;
  h.serial = config.serial.port;
  h.width = config.width();
  h.height = config.height();
  h.sections = config.sections;
  return h;
}

Board::Board(const BoardConfig& config) : Board(hardware_config(config)) {}

Board::Board(hal::HardwareConfig hardware)
    : hardware_(std::move(hardware)),
      left_(hardware_.camera(hal::Side::left), hardware_.clock()),
      right_(hardware_.camera(hal::Side::right), hardware_.clock()) {
  left_.pair_with(right_);
  if (hal::SerialPort* port = hardware_.serial()) {
    serial_ = std::make_unique<hal::RecoveringSerialPort>(*port, hardware_.clock());
  }
}

Board::~Board() = default;

std::string Board::serial_peer() const {
  return serial_ ? hardware_.serial()->peer_path() : std::string();
}

}  // namespace epipole::firmware
