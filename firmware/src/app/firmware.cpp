#include "epipole/firmware/firmware.hpp"

#include <pthread.h>
#include <sched.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "epipole/core/error.hpp"
#include "epipole/core/mcap_reader.hpp"
#include "epipole/core/temporary_folder.hpp"
#include "epipole/firmware/thread_roles.hpp"
#include "epipole/hal/registry.hpp"
#include "record/recorded_calibration.hpp"

namespace epipole::firmware {

namespace {

void check_budget(const std::string& board, std::optional<std::size_t> budget, std::size_t needed) {
  if (!budget) return;
  require(needed <= *budget, "board ", board, ": memory_budget_mb: the frame loop needs ",
          needed / 1024, " KiB but the budget is ", *budget / 1024, " KiB");
}

// The calibration file (or recording, whose calibration rides in it) the section of the cameras'
// backend names, if any.
std::filesystem::path backend_calibration(const BoardConfig& config) {
  const char* section =
      hal::BackendRegistry::builtin().camera_traits(config.cameras.backend).section;
  const hal::BackendSettings* settings = section ? config.sections.find(section) : nullptr;
  return settings != nullptr ? settings->calibration() : std::filesystem::path();
}

// Not there, rather than there but unreadable (that one is an error when it is loaded).
bool not_there(const std::filesystem::path& file) {
  std::error_code ec;
  return std::filesystem::status(file, ec).type() == std::filesystem::file_type::not_found;
}

}  // namespace

std::filesystem::path board_calibration_file(const BoardConfig& config) {
  const std::filesystem::path file = backend_calibration(config);
  return file.empty() ? config.calibration : file;
}

std::optional<calib::StereoCalibration> load_board_calibration(const BoardConfig& config) {
  if (const std::filesystem::path file = backend_calibration(config); !file.empty()) {
    if (mcap::is_mcap_file(file)) return record::recorded_calibration(file);
    return calib::load_calibration(file);
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
  // Each thread takes its own priority when it starts (thread_roles.hpp): none is real-time
  // before the firmware's threads and libcamera's exist.
  set_realtime_base(threads.realtime_priority);
  return problems;
}

Firmware::Firmware(BoardConfig config) : config_(std::move(config)) {
  build(std::make_unique<Board>(config_));
}

Firmware::Firmware(BoardConfig config, std::unique_ptr<Board> board, bool offline)
    : config_(std::move(config)) {
  build(std::move(board), offline);
}

Firmware::~Firmware() = default;

void Firmware::build(std::unique_ptr<Board> board, bool offline) {
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
  link.odometry =
      protocol::has_stage(config_.stages & pipeline_->available(), protocol::Stage::odometry) &&
      protocol::has_stage(config_.stages, protocol::Stage::sparse) &&
      protocol::has_stage(config_.stages, protocol::Stage::corners);
  link_ = std::make_unique<Link>(board_->serial(), board_->clock(), link);
  outputs_ = std::make_unique<Outputs>(config_, calibration_, offline);
  loop_ = std::make_unique<FrameLoop>(config_, *board_, *pipeline_, *link_, outputs_.get());
  check_budget(config_.name, config_.memory_budget_bytes, working_set_bytes());
}

MemoryReport Firmware::memory_report() const {
  MemoryReport report;
  pipeline_->add_memory(report);
  report.add("link", link_->working_set_bytes());
  loop_->add_memory(report);
  report.add(kCameras, board_->left().working_set_bytes() + board_->right().working_set_bytes() +
                           board_->hardware().backend_bytes());
  return report;
}

MemoryReport check_memory(BoardConfig config) {
  config.serial.backend = std::string(hal::kNoBackend);  // the link's queue is made all the same
  std::optional<TemporaryFolder> snapshots;
  if (!config.snapshot_directory.empty()) {
    snapshots.emplace("epipole-check");
    config.snapshot_directory = snapshots->path();
  }
  const std::string board = config.name;
  const std::optional<std::size_t> budget = config.memory_budget_bytes;
  config.memory_budget_bytes.reset();  // checked below, without the stand-ins' images
  hal::HardwareConfig hardware = hardware_config(config);
  const bool stand_in = hal::stand_in_for_devices(hardware);
  MemoryReport report =
      Firmware(std::move(config), std::make_unique<Board>(std::move(hardware)), true)
          .memory_report();
  if (stand_in) {
    std::erase_if(report.parts(),
                  [](const MemoryReport::Part& p) { return p.name == Firmware::kCameras; });
  }
  check_budget(board, budget, report.total());
  return report;
}

RunSummary Firmware::run(std::uint64_t max_frames, const std::atomic<bool>& stop) {
  return loop_->run(max_frames, stop);
}

}  // namespace epipole::firmware
