#include "epipole/firmware/board.hpp"

#include "epipole/core/error.hpp"
#include "epipole/hal/pty_serial.hpp"
#include "epipole/hal/registry.hpp"

namespace epipole::firmware {

namespace {

hal::SimCameraTiming sim_timing(const BoardConfig& c) {
  hal::SimCameraTiming t;
  t.seed = c.sim.seed;
  return t;
}

}  // namespace

Board::Board(const BoardConfig& config)
    : Board(config, config.cameras.backend == "sim" ? load_scene_images(config) : SceneImages{}) {}

Board::Board(const BoardConfig& config, SceneImages sim_images) {
  hal::BackendContext context;
  if (config.cameras.backend == "sim") {
    require(!sim_images.left.empty(), "board ", config.name,
            ": the simulated cameras have no images");
    sim_ = std::make_unique<hal::SimBoard>(config.trigger.line, std::move(sim_images.left),
                                           std::move(sim_images.right), sim_timing(config));
    clock_ = &sim_->clock;
    context.sim = sim_.get();
  } else {
    monotonic_ = std::make_unique<hal::MonotonicClock>();
    clock_ = monotonic_.get();
  }
  context.clock = clock_;
  const hal::BackendRegistry& registry = hal::BackendRegistry::builtin();
  left_camera_ = registry.create_camera(config.cameras.backend, config.cameras.left, context);
  right_camera_ = registry.create_camera(config.cameras.backend, config.cameras.right, context);
  left_ = std::make_unique<hal::RecoveringCamera>(*left_camera_, *clock_);
  right_ = std::make_unique<hal::RecoveringCamera>(*right_camera_, *clock_);
  if (sim_) {
    hal::SimFaultRates rates;
    rates.drop = config.sim.drop_rate;
    rates.corrupt_pixels = config.sim.corrupt_rate;
    rates.seed = config.sim.seed;
    sim_camera(hal::Side::left)->set_fault_rates(rates);
    rates.seed = config.sim.seed * 2654435761u + 1;  // independent faults per side
    sim_camera(hal::Side::right)->set_fault_rates(rates);
  }
  if (config.trigger.backend != "none") {
    trigger_ = registry.create_trigger(config.trigger.backend, config.trigger.line, context);
  }
  if (config.serial.backend != "none") {
    port_ = registry.create_serial(config.serial.backend, config.serial.port, context);
    serial_ = std::make_unique<hal::RecoveringSerialPort>(*port_, *clock_);
  }
}

Board::~Board() = default;

std::string Board::serial_peer() const {
  const auto* pty = dynamic_cast<const hal::PtySerialPort*>(port_.get());
  return pty != nullptr ? pty->peer_path() : std::string();
}

hal::SimCamera* Board::sim_camera(hal::Side side) {
  return dynamic_cast<hal::SimCamera*>(side == hal::Side::left ? left_camera_.get()
                                                               : right_camera_.get());
}

}  // namespace epipole::firmware
