// The "sim" camera and trigger backends: parts of the simulated board (sim.hpp) that the
// registry hands out like any other device.
#include <memory>

#include "backends.hpp"
#include "epipole/core/error.hpp"
#include "epipole/hal/registry.hpp"
#include "sim/sim.hpp"

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

std::unique_ptr<CameraSource> make_camera(const CameraConfig& config,
                                          const BackendContext& context) {
  require(context.sim != nullptr, "camera ", config.device,
          ": backend 'sim' needs the simulated board");
  require(config.device == "left" || config.device == "right", "camera ", config.device,
          ": the simulated board has cameras 'left' and 'right'");
  SimBoard& board = *context.sim;
  const bool left = config.device == "left";
  SimCameraTiming timing = board.timing;
  if (!left) timing.seed = timing.seed * 0x9e3779b97f4a7c15ULL + 1;  // independent jitter
  auto camera =
      std::make_unique<SimCamera>(config, left ? board.left : board.right, board.clock, timing);
  // A free-running camera ignores the trigger line: it runs on its own at its frame rate.
  if (config.trigger == TriggerMode::external) board.trigger.connect(*camera);
  board.cameras[left ? 0 : 1] = camera.get();
  return camera;
}

std::unique_ptr<TriggerLine> make_trigger(const TriggerConfig& config,
                                          const BackendContext& context) {
  require(context.sim != nullptr, "trigger ", config.line,
          ": backend 'sim' needs the simulated board");
  return std::make_unique<SimTriggerHandle>(context.sim->trigger);
}

}  // namespace

void register_sim(BackendRegistry& registry) {
  registry.add_camera("sim", make_camera, {.simulated = true});
  registry.add_trigger("sim", make_trigger, {.simulated = true});
}

}  // namespace epipole::hal
