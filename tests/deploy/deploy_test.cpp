// The deployment test (docs/deploy.md): the board package installed with apt on Debian bookworm
// arm64 booted with systemd under qemu-system-aarch64, then run, faulted, upgraded, disabled,
// removed and purged. The guest's script (tests/deploy/guest/run.sh) checks what an admin sees
// there (systemctl, the journal, dpkg) and prints a verdict per step; this test reads those on
// the console, and decodes what the firmware sent on the board's UARTs.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <variant>
#include <vector>

#include "epipole/firmware/protocol/codec.hpp"
#include "test_paths.hpp"
#include "virtual_board.hpp"

namespace epipole::test {
namespace {

// scripts/deploy/prepare.sh made it, beside this program
const std::string kRun = (program_folder() / "run").string();

std::vector<std::string> lines_with(const std::string& text, const std::string& marker) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (const auto at = line.find(marker); at != std::string::npos) out.push_back(line.substr(at));
  }
  return out;
}

std::vector<protocol::DecodedMessage> decode_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::vector<protocol::DecodedMessage> out;
  protocol::FrameDecoder decoder;
  for (char c; in.get(c);) {
    if (auto m = decoder.push(static_cast<std::uint8_t>(c))) out.push_back(*m);
  }
  return out;
}

template <typename T>
std::vector<T> all_of(const std::vector<protocol::DecodedMessage>& messages) {
  std::vector<T> out;
  for (const auto& m : messages) {
    if (const T* t = std::get_if<T>(&m.message)) out.push_back(*t);
  }
  return out;
}

// The robot asks for a snapshot once the admin's board has streamed 10 pairs (the guest checks
// the files in the service's state folder).
constexpr std::uint16_t kSnapshotCommand = 1;
Robot snapshot_after_ten_pairs() {
  return [pairs = 0](const protocol::DecodedMessage& m) mutable {
    std::vector<std::uint8_t> bytes;
    if (std::holds_alternative<protocol::FrameSummary>(m.message) && ++pairs == 10) {
      bytes.resize(protocol::kMaxFrameSize);
      bytes.resize(protocol::encode_frame(protocol::Snapshot{}, kSnapshotCommand, bytes));
    }
    return bytes;
  };
}

TEST(Deployment, InstallRunFaultsUpgradesRemoveAndPurge) {
  const std::string uart0 = ::testing::TempDir() + "deploy-uart0.bin";
  std::remove(uart0.c_str());
  const BoardRun run = run_board({std::string(source_dir()) + "/scripts/deploy/boot.sh",
                                  kRun + "/rootfs", kRun + "/disk.qcow2", kRun + "/payload.img"},
                                 "EPIPOLE_DEPLOY_LINK", {{"EPIPOLE_DEPLOY_UART0", uart0}}, "deploy",
                                 900, 0, snapshot_after_ten_pairs());
  const std::vector<std::string> verdicts = lines_with(run.console, "deploy: ");
  for (const std::string& v : verdicts) std::printf("  %s\n", v.c_str());
  std::printf("  (the guest ran %.0f s)\n", run.seconds);

  EXPECT_EQ(run.exit_code, 0) << "QEMU";
  EXPECT_TRUE(lines_with(run.console, "deploy: FAILED").empty()) << run.console;
  ASSERT_EQ(lines_with(run.console, "deploy: all passed").size(), 1u) << run.console;
  // The steps the issue names, each checked in the guest.
  for (const char* step : {"apt install epipole_",
                           "enabled on the first install",
                           "active (running) with the package's board file",
                           "runs as the epipole user",
                           "journal: not calibrated",
                           "journal: waits for the missing cameras",
                           "journal: waits for the missing trigger line",
                           "no crash loop",
                           "watchdog pinged",
                           "only the trigger's chip for the gpio group",
                           "restarted with the edited board file",
                           "frame loop and workers SCHED_FIFO 50",
                           "vision worker SCHED_FIFO 50",
                           "link thread SCHED_FIFO 51",
                           "trigger thread SCHED_FIFO 52",
                           "snapshot thread at normal scheduling",
                           "the firmware's threads on CPU 1",
                           "memory locked",
                           "snapshot written in the state folder",
                           "restarted after kill -9",
                           "journal: cameras recovered",
                           "recovered without a restart",
                           "the edited board file kept",
                           "restarted by the upgrade",
                           "still disabled",
                           "the board file kept (a conffile)",
                           "purged: nothing of the package left"}) {
    EXPECT_FALSE(lines_with(run.console, std::string("deploy: ok: ") + step).empty()) << step;
  }

  // The package's own board file (the Raspberry Pi 5's) on a board without its cameras and
  // trigger line: the firmware ran on its UART (the PL011), sending health that says why
  // nothing is processed (no calibration, no cascade, no trigger edge).
  const auto pi_health = all_of<protocol::Health>(decode_file(uart0));
  ASSERT_GE(pi_health.size(), 3u) << "health on /dev/ttyAMA0 from the package's board file";
  for (const protocol::Health& h : pi_health) {
    EXPECT_EQ(h.frames, 0u);
    EXPECT_EQ(h.flags, protocol::kHealthNotCalibrated | protocol::kHealthNoCascade |
                           protocol::kHealthWaitingForTrigger);
  }
  EXPECT_GE(pi_health.back().trigger_losses, 1u) << "the trigger line is not there";

  // The admin's board file: pairs streamed over the link UART, uncalibrated, by three runs of
  // the firmware at least (the edited board, after kill -9, after the upgrade).
  const auto frames = run.all<protocol::FrameSummary>();
  const auto health = run.all<protocol::Health>();
  EXPECT_GE(frames.size(), 40u);
  ASSERT_GE(health.size(), 10u);
  // The trigger's edges follow the cameras' frames here: while the cameras are gone (step 4),
  // or before their first frame, health also says it waits for the trigger.
  for (const protocol::Health& h : health) {
    EXPECT_EQ(h.flags & ~protocol::kHealthWaitingForTrigger, protocol::kHealthNotCalibrated);
  }
  int runs = 1;
  for (std::size_t i = 1; i < health.size(); ++i) {
    if (health[i].uptime_ms < health[i - 1].uptime_ms) ++runs;
  }
  EXPECT_GE(runs, 3) << "health uptimes start again with each start of the service";
  std::printf("  link: %zu frame summaries, %zu health messages from %d runs; PL011: %zu health\n",
              frames.size(), health.size(), runs, pi_health.size());
  EXPECT_TRUE(std::any_of(health.begin(), health.end(), [](const protocol::Health& h) {
    return h.camera_reopens >= 2;
  })) << "the cameras' reload is counted";
  // The snapshot, answered once written and synced.
  const auto acks = run.all<protocol::CommandAck>();
  ASSERT_EQ(acks.size(), 1u);
  EXPECT_EQ(acks[0].command_sequence, kSnapshotCommand);
  EXPECT_EQ(acks[0].status, protocol::AckStatus::ok);
}

}  // namespace
}  // namespace epipole::test
