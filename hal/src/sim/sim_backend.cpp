// The "sim" camera and trigger backends: parts of the simulated board (sim.hpp) that the
// registry hands out like any other device, and the board file's `sim:` section they share.
#include <memory>

#include "backends.hpp"
#include "epipole/core/error.hpp"
#include "epipole/hal/hardware.hpp"
#include "epipole/hal/registry.hpp"
#include "sim/sim.hpp"
#include "sim/sim_settings.hpp"

namespace epipole::hal {

namespace {

// The board's trigger, lent to whoever asked the registry for the "sim" trigger.
class SimTriggerHandle final : public TriggerLine {
 public:
  explicit SimTriggerHandle(SimTrigger& trigger) : trigger_(trigger) {}
  const TriggerConfig& config() const override { return trigger_.config(); }
  void start() override { trigger_.start(); }
  void stop() override { trigger_.stop(); }
  EdgeResult wait_edge(Nanoseconds timeout) override { return trigger_.wait_edge(timeout); }
  void set_rate(double rate_hz) override { trigger_.set_rate(rate_hz); }
  bool record_edges_to(TriggerRecord* record) override { return trigger_.record_edges_to(record); }

 private:
  SimTrigger& trigger_;
};

SimBoard& board_of(const BackendContext& context, const std::string& part) {
  auto* board = dynamic_cast<SimBoard*>(context.board);
  require(board != nullptr, part, ": backend 'sim' needs the simulated board");
  return *board;
}

std::unique_ptr<CameraSource> make_camera(const CameraConfig& config,
                                          const BackendContext& context) {
  SimBoard& board = board_of(context, "camera " + config.device);
  require(config.device == "left" || config.device == "right", "camera ", config.device,
          ": the simulated board has cameras 'left' and 'right'");
  const bool left = config.device == "left";
  SimCameraTiming timing = board.timing;
  if (!left) timing.seed = timing.seed * 0x9e3779b97f4a7c15ULL + 1;  // independent jitter
  auto camera =
      std::make_unique<SimCamera>(config, left ? board.left : board.right, board.clock, timing);
  SimFaultRates rates = board.fault_rates;
  if (!left) rates.seed = rates.seed * 2654435761u + 1;  // independent faults per side
  camera->set_fault_rates(rates);
  // A free-running camera ignores the trigger line: it runs on its own at its frame rate.
  if (config.trigger == TriggerMode::external) board.trigger.connect(*camera);
  board.cameras[left ? 0 : 1] = camera.get();
  return camera;
}

std::unique_ptr<TriggerLine> make_trigger(const TriggerConfig& config,
                                          const BackendContext& context) {
  return std::make_unique<SimTriggerHandle>(board_of(context, "trigger " + config.line).trigger);
}

// The simulated board of a board file: its scene (or the images given instead), its clock and
// its random faults.
std::unique_ptr<BackendBoard> make_board(const BackendSettings& settings,
                                         const HardwareConfig& config) {
  const auto& sim = dynamic_cast<const SimSettings&>(settings);
  const std::shared_ptr<const StereoImages> images =
      sim.images ? sim.images
                 : std::make_shared<const StereoImages>(
                       load_scene(sim.chosen(), config.width, config.height));
  require(!images->left.empty(), "the simulated cameras have no images");
  SimCameraTiming timing;
  timing.seed = sim.seed;
  // Without a trigger line the board's master is there all the same (unused: free running).
  TriggerConfig trigger = config.trigger;
  if (trigger.line.empty()) trigger.line = "sim";
  auto board = std::make_unique<SimBoard>(trigger, images, timing);
  board->clock.charge_compute(sim.charge_compute);
  board->fault_rates.drop = sim.drop_rate;
  board->fault_rates.corrupt_pixels = sim.corrupt_rate;
  board->fault_rates.seed = sim.seed;
  return board;
}

// Simulated cameras of the board's size (grey, whatever the board's cameras deliver: the frame
// loop sees gray planes either way) showing a blank image, and a simulated trigger master at the
// board's rate.
void stand_in(HardwareConfig& config) {
  config.camera_backend = "sim";
  for (auto [camera, name] : {std::pair{&config.left, "left"}, std::pair{&config.right, "right"}}) {
    camera->device = name;
    camera->format = PixelFormat::grey;
  }
  if (config.trigger_backend != kNoBackend) {
    config.trigger_backend = "sim";
    config.trigger.role = TriggerRole::master;
  }
  auto sim = std::make_unique<SimSettings>();
  auto blank = std::make_shared<StereoImages>();
  blank->left.emplace_back(config.width, config.height);
  blank->right.emplace_back(config.width, config.height);
  sim->images = std::move(blank);
  config.sections.set("sim", std::move(sim));
}

}  // namespace

void register_sim(BackendRegistry& registry) {
  registry.add_camera("sim", make_camera, {.simulated = true, .section = "sim"});
  registry.add_trigger("sim", make_trigger, {.simulated = true, .section = "sim"});
  registry.add_section({"sim", read_sim_section, make_board, stand_in});
}

}  // namespace epipole::hal
