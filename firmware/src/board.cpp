#include "epipole/firmware/board.hpp"

#include <utility>

namespace epipole::firmware {

namespace {

hal::HardwareConfig hardware_config(const BoardConfig& config, SceneImages sim_images) {
  hal::HardwareConfig h;
  h.camera_backend = config.cameras.backend;
  h.left = config.cameras.left;
  h.right = config.cameras.right;
  h.trigger_backend = config.trigger.backend;
  h.trigger = config.trigger.line;
  h.serial_backend = config.serial.backend;
  h.serial = config.serial.port;
  h.sim.left = std::move(sim_images.left);
  h.sim.right = std::move(sim_images.right);
  h.sim.seed = config.sim.seed;
  h.sim.drop_rate = config.sim.drop_rate;
  h.sim.corrupt_rate = config.sim.corrupt_rate;
  h.sim.charge_compute = config.sim.charge_compute;
  return h;
}

}  // namespace

Board::Board(const BoardConfig& config)
    : Board(config, config.simulated() ? load_scene_images(config) : SceneImages{}) {}

Board::Board(const BoardConfig& config, SceneImages sim_images)
    : hardware_(hardware_config(config, std::move(sim_images))),
      left_(hardware_.camera(hal::Side::left), hardware_.clock()),
      right_(hardware_.camera(hal::Side::right), hardware_.clock()) {
  if (hal::SerialPort* port = hardware_.serial()) {
    serial_ = std::make_unique<hal::RecoveringSerialPort>(*port, hardware_.clock());
  }
}

Board::~Board() = default;

std::string Board::serial_peer() const {
  return serial_ ? hardware_.serial()->peer_path() : std::string();
}

}  // namespace epipole::firmware
