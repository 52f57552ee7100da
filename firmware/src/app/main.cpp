// epipole-fw: the firmware. Loads a board's configuration, allocates everything, then runs the
// frame loop until SIGTERM or SIGINT (or --frames pairs), speaking to the service manager when
// it runs as a service.
#include <sys/mman.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>

#include "epipole/core/error.hpp"
#include "epipole/firmware/build_info.hpp"
#include "epipole/firmware/cascade_file.hpp"
#include "epipole/firmware/firmware.hpp"
#include "epipole/firmware/journal.hpp"
#include "epipole/firmware/pipeline.hpp"
#include "epipole/firmware/service.hpp"

using epipole::firmware::journal;
using epipole::firmware::Priority;

namespace {

std::atomic<bool> g_stop{false};

extern "C" void on_signal(int) {
  g_stop.store(true);
}

void install_signal_handlers() {
  struct sigaction action {};
  action.sa_handler = on_signal;
  sigemptyset(&action.sa_mask);
  sigaction(SIGTERM, &action, nullptr);
  sigaction(SIGINT, &action, nullptr);
  signal(SIGPIPE, SIG_IGN);
}

// One journal line for each thing a fresh board runs without (a calibration, a compiled
// cascade), with how to make it.
void say_what_runs_without(epipole::firmware::Firmware& fw) {
  using namespace epipole;
  if (!fw.missing_calibration().empty()) {
    journal(Priority::warning,
            "not calibrated: %s does not exist yet; running uncalibrated (images taken as "
            "rectified, no depth, health flags say so). Calibrate on the board: snapshots, "
            "`epipole calibrate ... -o %s`, restart (docs/deploy.md)",
            fw.missing_calibration().c_str(), fw.missing_calibration().c_str());
  } else if (!fw.calibration()) {
    journal(Priority::warning,
            "warning: no calibration: images are taken as rectified and nothing gets a depth");
  }
  if (const std::filesystem::path& cascade = fw.pipeline().missing_cascade(); !cascade.empty()) {
    journal(Priority::warning,
            "no detection: the cascade %s does not exist yet; running without it. Make it with "
            "`%s` and restart (docs/deploy.md)",
            cascade.c_str(), firmware::cascade_compile_command(cascade).c_str());
  }
}

// --check: the board file validated and the frame loop's memory made and measured part by part,
// with stand-ins for the devices (none is opened). 0 when the board would start, 1 otherwise.
int check_board(const epipole::firmware::BoardConfig& config, const std::string& board_path) {
  using namespace epipole;
  const firmware::MemoryReport report = firmware::check_memory(config);
  std::printf("epipole-fw: %s: board %s, %dx%d, valid\n", board_path.c_str(), config.name.c_str(),
              config.width(), config.height());
  if (!config.calibration.empty() && !std::filesystem::exists(config.calibration)) {
    std::printf("  not calibrated yet (%s): rectification not counted\n",
                config.calibration.c_str());
  }
  for (const firmware::MemoryReport::Part& part : report.parts()) {
    std::printf("  %-18s %10zu KiB\n", part.name.c_str(), (part.bytes + 1023) / 1024);
  }
  std::printf("  %-18s %10zu KiB", "total", (report.total() + 1023) / 1024);
  if (config.memory_budget_bytes) {
    std::printf(" of a budget of %zu KiB", *config.memory_budget_bytes / 1024);
  }
  std::printf("\n");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace epipole;
  CLI::App app{"Epipole stereo-vision firmware: runs a board's frame loop.", "epipole-fw"};
  app.set_version_flag("--version", firmware::build_info());
  std::string board_path;
  std::uint64_t frames = 0;
  std::string scene;
  app.add_option("--board", board_path, "Board folder (with board.yaml) or board file")->required();
  app.add_option("--frames", frames, "Stop after this many frame pairs (0: run until stopped)");
  app.add_option("--scene", scene,
                 "The scene the cameras replay, on a board whose cameras' backend has scenes "
                 "(default: the board file's)");
  bool check = false;
  app.add_flag("--check", check,
               "Validate the board file and print the frame loop's memory per stage, opening no "
               "device; exit 0 when the board would start");
  CLI11_PARSE(app, argc, argv);

  firmware::ServiceNotifier service;
  try {
    std::vector<hal::BackendOption> camera_options;
    if (!scene.empty()) camera_options.push_back({"scene", scene});
    firmware::BoardConfig config = firmware::load_board_config(board_path, {}, camera_options);
    if (const std::string problem = firmware::watchdog_problem(config, service.watchdog_interval());
        !problem.empty()) {
      throw Error(board_path + ": " + problem);
    }
    if (check) return check_board(config, board_path);
    install_signal_handlers();
    for (const std::string& problem : firmware::apply_scheduling(config.threads)) {
      journal(Priority::warning, "warning: %s", problem.c_str());
    }
    firmware::Firmware fw(std::move(config));
    if (fw.config().threads.lock_memory && mlockall(MCL_CURRENT | MCL_FUTURE) != 0) {
      journal(Priority::warning, "warning: threads.lock_memory: mlockall failed: %s",
              std::strerror(errno));
    }
    journal(Priority::info, "board %s, %dx%d, %zu KiB of frame buffers%s%s",
            fw.config().name.c_str(), fw.config().width(), fw.config().height(),
            fw.working_set_bytes() / 1024, fw.board().serial_peer().empty() ? "" : ", link at ",
            fw.board().serial_peer().c_str());
    say_what_runs_without(fw);
    fw.frame_loop().set_heartbeat([&service] { service.watchdog(); });
    service.ready();
    service.status("running");
    const firmware::RunSummary s = fw.run(frames, g_stop);
    service.stopping();
    journal(Priority::info,
            "stopped after %llu pairs (%llu stale, %llu timeouts), %llu health messages, %llu "
            "messages sent, %llu dropped",
            static_cast<unsigned long long>(s.frames), static_cast<unsigned long long>(s.stale),
            static_cast<unsigned long long>(s.timeouts),
            static_cast<unsigned long long>(s.health_messages),
            static_cast<unsigned long long>(s.link.messages_sent),
            static_cast<unsigned long long>(s.link.messages_dropped));
  } catch (const Error& e) {
    journal(Priority::error, "%s", e.what());
    return 1;
  } catch (const std::exception& e) {
    journal(Priority::error, "internal error: %s", e.what());
    return 2;
  }
  return 0;
}
