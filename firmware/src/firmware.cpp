#include "epipole/firmware/firmware.hpp"

#include <pthread.h>
#include <sched.h>

#include <cstring>

#include "epipole/core/error.hpp"

namespace epipole::firmware {

namespace {

const BoardConfig::SimScene* scene_with_calibration(const BoardConfig& config) {
  const BoardConfig::SimScene* scene = config.sim_scene();
  return scene != nullptr && config.simulated() && !scene->calibration.empty() ? scene : nullptr;
}

// Not there, rather than there but unreadable (that one is an error when it is loaded).
bool not_there(const std::filesystem::path& file) {
  std::error_code ec;
  return std::filesystem::status(file, ec).type() == std::filesystem::file_type::not_found;
}

}  // namespace

std::optional<calib::StereoCalibration> load_board_calibration(const BoardConfig& config) {
  if (const BoardConfig::SimScene* scene = scene_with_calibration(config)) {
    return calib::load_calibration(scene->calibration);
  }
  if (config.calibration.empty() || not_there(config.calibration)) return std::nullopt;
  return calib::load_calibration(config.calibration);
}

std::vector<std::string> apply_scheduling(const BoardConfig::Threads& threads) {
  std::vector<std::string> problems;
  if (!threads.affinity.empty()) {
    cpu_set_t set;
    CPU_ZERO(&set);
    for (const int cpu : threads.affinity) CPU_SET(static_cast<std::size_t>(cpu), &set);
    if (const int rc = pthread_setaffinity_np(pthread_self(), sizeof set, &set); rc != 0) {
      problems.push_back(cat("threads.affinity: cannot pin the threads: ", std::strerror(rc)));
    }
  }
  if (threads.realtime_priority > 0) {
    sched_param param{};
    param.sched_priority = threads.realtime_priority;
    if (const int rc = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param); rc != 0) {
      problems.push_back(cat("threads.realtime_priority: cannot use SCHED_FIFO priority ",
                             threads.realtime_priority, ": ", std::strerror(rc),
                             " (the service needs CAP_SYS_NICE or an rtprio limit)"));
    }
  }
  return problems;
}

Firmware::Firmware(BoardConfig config) : config_(std::move(config)) {
  build(std::make_unique<Board>(config_));
}

Firmware::Firmware(BoardConfig config, SceneImages sim_images) : config_(std::move(config)) {
  build(std::make_unique<Board>(config_, std::move(sim_images)));
}

Firmware::~Firmware() = default;

void Firmware::build(std::unique_ptr<Board> board) {
  calibration_ = load_board_calibration(config_);
  board_ = std::move(board);
  pipeline_ = std::make_unique<Pipeline>(config_, calibration_);
  LinkConfig link;
  link.protocol = config_.serial.protocol == BoardConfig::LinkProtocol::mavlink
                      ? LinkProtocol::mavlink
                      : LinkProtocol::epipole;
  link.identity.system_id = config_.serial.mavlink_system_id;
  link.identity.component_id = config_.serial.mavlink_component_id;
  link.baud = config_.serial.port.baud;
  link_ = std::make_unique<Link>(board_->serial(), board_->clock(), link);
  loop_ = std::make_unique<FrameLoop>(config_, *board_, *pipeline_, *link_);
  if (config_.memory_budget_bytes) {
    require(working_set_bytes() <= *config_.memory_budget_bytes, "board ", config_.name,
            ": memory_budget_mb: the frame loop needs ", working_set_bytes() / 1024,
            " KiB but the "
            "budget is ",
            *config_.memory_budget_bytes / 1024, " KiB");
  }
}

std::size_t Firmware::working_set_bytes() const {
  return pipeline_->working_set_bytes() + LinkConfig{}.queue_bytes;
}

RunSummary Firmware::run(std::uint64_t max_frames, const std::atomic<bool>& stop) {
  return loop_->run(max_frames, stop);
}

}  // namespace epipole::firmware
