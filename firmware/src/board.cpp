#include "epipole/firmware/board.hpp"

#include "epipole/core/error.hpp"
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
    : Board(config, config.simulated() ? load_scene_images(config) : SceneImages{}) {}

Board::Board(const BoardConfig& config, SceneImages sim_images) {
  hal::BackendContext context;
  if (config.simulated()) {
    require(!sim_images.left.empty(), "board ", config.name,
            ": the simulated cameras have no images");
    sim_ = std::make_unique<hal::SimBoard>(config.trigger.line, std::move(sim_images.left),
                                           std::move(sim_images.right), sim_timing(config));
    sim_->clock.charge_compute(config.sim.charge_compute);
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
  if (config.has_trigger()) {
    trigger_ = registry.create_trigger(config.trigger.backend, config.trigger.line, context);
  }
  if (config.has_link()) {
    port_ = registry.create_serial(config.serial.backend, config.serial.port, context);
    serial_ = std::make_unique<hal::RecoveringSerialPort>(*port_, *clock_);
  }
}

Board::~Board() = default;

std::string Board::serial_peer() const {
  return port_ ? port_->peer_path() : std::string();
}

hal::SimCamera* Board::sim_camera(hal::Side side) {
  return sim_ ? sim_->camera(side) : nullptr;
}

}  // namespace epipole::firmware
