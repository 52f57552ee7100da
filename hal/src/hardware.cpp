#include "epipole/hal/hardware.hpp"

#include <utility>

#include "epipole/core/error.hpp"
#include "sim/sim.hpp"

namespace epipole::hal {

namespace {

std::unique_ptr<SimBoard> make_sim_board(HardwareConfig& config) {
  require(!config.sim.left.empty(), "the simulated cameras have no images");
  SimCameraTiming timing;
  timing.seed = config.sim.seed;
  auto board = std::make_unique<SimBoard>(config.trigger, std::move(config.sim.left),
                                          std::move(config.sim.right), timing);
  board->clock.charge_compute(config.sim.charge_compute);
  return board;
}

void set_random_faults(SimBoard& board, const SimSettings& settings) {
  SimFaultRates rates;
  rates.drop = settings.drop_rate;
  rates.corrupt_pixels = settings.corrupt_rate;
  rates.seed = settings.seed;
  board.camera(Side::left)->set_fault_rates(rates);
  rates.seed = settings.seed * 2654435761u + 1;  // independent faults per side
  board.camera(Side::right)->set_fault_rates(rates);
}

}  // namespace

Hardware::Hardware(HardwareConfig config, const BackendRegistry& registry) {
  BackendContext context;
  if (registry.camera_traits(config.camera_backend).simulated) {
    sim_ = make_sim_board(config);
    clock_ = &sim_->clock;
    context.sim = sim_.get();
  }
  context.clock = clock_;
  cameras_[index(Side::left)] = registry.create_camera(config.camera_backend, config.left, context);
  cameras_[index(Side::right)] =
      registry.create_camera(config.camera_backend, config.right, context);
  if (sim_) set_random_faults(*sim_, config.sim);
  if (config.trigger_backend != kNoBackend) {
    trigger_ = registry.create_trigger(config.trigger_backend, config.trigger, context);
  }
  if (config.serial_backend != kNoBackend) {
    serial_ = registry.create_serial(config.serial_backend, config.serial, context);
  }
}

Hardware::~Hardware() = default;

std::size_t Hardware::scene_images() const {
  return sim_ ? sim_->left->size() : 0;
}

std::size_t Hardware::scene_bytes() const {
  std::size_t bytes = 0;
  if (sim_) {
    for (const auto* side : {sim_->left.get(), sim_->right.get()}) {
      for (const GrayImage& image : *side) bytes += image.size_bytes();
    }
  }
  return bytes;
}

}  // namespace epipole::hal
