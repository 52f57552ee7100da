#include "epipole/hal/registry.hpp"

#include <algorithm>

#include "epipole/core/error.hpp"
#include "epipole/hal/gpiod_trigger.hpp"
#include "epipole/hal/libcamera_camera.hpp"
#include "epipole/hal/pty_serial.hpp"
#include "epipole/hal/sim.hpp"
#include "epipole/hal/v4l2_camera.hpp"

namespace epipole::hal {

namespace {

template <typename Entries>
std::string names_of(const Entries& entries) {
  std::string names;
  for (const auto& e : entries) {
    if (!names.empty()) names += ", ";
    names += e.name;
    if (!e.unavailable.empty()) names += " (not built)";
  }
  return names;
}

template <typename Entries>
const auto& find_entry(const Entries& entries, std::string_view kind, std::string_view backend,
                       const std::string& target) {
  const auto it = std::find_if(entries.begin(), entries.end(),
                               [&](const auto& e) { return e.name == backend; });
  if (it == entries.end()) {
    throw Error(cat(kind, " ", target, ": unknown backend '", backend,
                    "' (known: ", names_of(entries), ")"));
  }
  if (!it->unavailable.empty()) {
    throw Error(cat(kind, " ", target, ": backend '", backend,
                    "' is not built into this binary: ", it->unavailable));
  }
  return *it;
}

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

BackendRegistry make_builtin() {
  BackendRegistry r;
  r.add_camera("sim",
               [](const CameraConfig& config, const BackendContext& context) {
                 require(context.sim != nullptr, "camera ", config.device,
                         ": backend 'sim' needs the simulated board");
                 require(config.device == "left" || config.device == "right", "camera ",
                         config.device, ": the simulated board has cameras 'left' and 'right'");
                 SimBoard& board = *context.sim;
                 const bool left = config.device == "left";
                 SimCameraTiming timing = board.timing;
                 if (!left)
                   timing.seed = timing.seed * 0x9e3779b97f4a7c15ULL + 1;  // independent jitter
                 auto camera = std::make_unique<SimCamera>(config, left ? board.left : board.right,
                                                           board.clock, timing);
                 // A free-running camera ignores the trigger line: it runs on its own at its frame
                 // rate.
                 if (config.trigger == TriggerMode::external) board.trigger.connect(*camera);
                 board.cameras[left ? 0 : 1] = camera.get();
                 return std::unique_ptr<CameraSource>(std::move(camera));
               },
               {.simulated = true});
  r.add_camera("v4l2",
               [](const CameraConfig& config, const BackendContext&) {
                 return std::unique_ptr<CameraSource>(std::make_unique<V4l2Camera>(config));
               },
               {.needs_device = true});
  register_libcamera(r);
  r.add_trigger("sim",
                [](const TriggerConfig& config, const BackendContext& context) {
                  require(context.sim != nullptr, "trigger ", config.line,
                          ": backend 'sim' needs the simulated board");
                  return std::unique_ptr<TriggerLine>(
                      std::make_unique<SimTriggerHandle>(context.sim->trigger));
                },
                {.simulated = true});
  register_gpiod(r);
  r.add_serial("termios",
               [](const SerialConfig& config, const BackendContext&) {
                 return std::unique_ptr<SerialPort>(std::make_unique<TermiosSerialPort>(config));
               },
               {.needs_device = true});
  r.add_serial("pty",
               [](const SerialConfig& config, const BackendContext&) {
                 return std::unique_ptr<SerialPort>(std::make_unique<PtySerialPort>(config));
               },
               {.simulated = true});
  return r;
}

}  // namespace

void BackendRegistry::add_camera(std::string name, CameraFactory factory, BackendTraits traits) {
  cameras_.push_back({std::move(name), std::move(factory), {}, traits});
}
void BackendRegistry::add_trigger(std::string name, TriggerFactory factory, BackendTraits traits) {
  triggers_.push_back({std::move(name), std::move(factory), {}, traits});
}
void BackendRegistry::add_serial(std::string name, SerialFactory factory, BackendTraits traits) {
  serials_.push_back({std::move(name), std::move(factory), {}, traits});
}
void BackendRegistry::add_unavailable_camera(std::string name, std::string reason,
                                             BackendTraits traits) {
  cameras_.push_back({std::move(name), {}, std::move(reason), traits});
}
void BackendRegistry::add_unavailable_trigger(std::string name, std::string reason,
                                              BackendTraits traits) {
  triggers_.push_back({std::move(name), {}, std::move(reason), traits});
}

std::unique_ptr<CameraSource> BackendRegistry::create_camera(std::string_view backend,
                                                             const CameraConfig& config,
                                                             const BackendContext& context) const {
  const auto& e = find_entry(cameras_, "camera", backend, config.device);
  validate(config);
  return e.factory(config, context);
}

std::unique_ptr<TriggerLine> BackendRegistry::create_trigger(std::string_view backend,
                                                             const TriggerConfig& config,
                                                             const BackendContext& context) const {
  const auto& e = find_entry(triggers_, "trigger", backend, config.line);
  validate(config);
  return e.factory(config, context);
}

std::unique_ptr<SerialPort> BackendRegistry::create_serial(std::string_view backend,
                                                           const SerialConfig& config,
                                                           const BackendContext& context) const {
  const auto& e = find_entry(serials_, "serial port", backend, config.device);
  return e.factory(config, context);
}

namespace {

template <typename Entries>
std::vector<std::string> name_list(const Entries& entries) {
  std::vector<std::string> names;
  for (const auto& e : entries) names.push_back(e.name);
  return names;
}

template <typename Entries>
BackendTraits traits_of(const Entries& entries, std::string_view backend) {
  for (const auto& e : entries) {
    if (e.name == backend) return e.traits;
  }
  return {};
}

}  // namespace

std::vector<std::string> BackendRegistry::camera_backends() const {
  return name_list(cameras_);
}
std::vector<std::string> BackendRegistry::trigger_backends() const {
  return name_list(triggers_);
}
std::vector<std::string> BackendRegistry::serial_backends() const {
  return name_list(serials_);
}
BackendTraits BackendRegistry::camera_traits(std::string_view backend) const {
  return traits_of(cameras_, backend);
}
BackendTraits BackendRegistry::trigger_traits(std::string_view backend) const {
  return traits_of(triggers_, backend);
}
BackendTraits BackendRegistry::serial_traits(std::string_view backend) const {
  return traits_of(serials_, backend);
}

const BackendRegistry& BackendRegistry::builtin() {
  static const BackendRegistry registry = make_builtin();
  return registry;
}

}  // namespace epipole::hal
