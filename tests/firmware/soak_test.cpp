// The soak: the simulated board with every stage, random faults on both cameras (drops, damaged
// frames, garbled sequences, delays), a camera lost and reopened every 3000 triggers (reopens
// that succeed: a failing one throws an Error, whose message allocates; frame_loop_tests cover
// those) and the robot's commands every 100 ms, a snapshot among them, for
// EPIPOLE_SOAK_SECONDS of wall time (20 unless set; the test command sets 300, docs/testing.md
// has longer runs by hand). After the warm-up (a tenth of the run, at least 5 s): anonymous
// resident memory grows by at most 1 MiB, the open file descriptors stay the same, nothing is
// allocated in any thread, and every health message accounts for every trigger.
#include <fcntl.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <span>
#include <thread>

#include "allocation_counter.hpp"
#include "epipole/firmware/firmware.hpp"
#include "sim_rig.hpp"
#include "termios/termios_serial.hpp"

namespace epipole::firmware {
namespace {

using Steady = std::chrono::steady_clock;

int soak_seconds() {
  const char* value = std::getenv("EPIPOLE_SOAK_SECONDS");
  const int seconds = value != nullptr ? std::atoi(value) : 0;
  return seconds > 0 ? seconds : 20;
}

// Resident memory from /proc/self/statm, read without allocating: the anonymous part (heap,
// stacks) and the file-backed part (code and data of the binaries, paged in as rarely taken
// paths first run, and given back under pressure). Only the anonymous part can be a leak.
struct Resident {
  std::size_t anonymous = 0, file = 0;
};
Resident resident_bytes() {
  const int fd = ::open("/proc/self/statm", O_RDONLY | O_CLOEXEC);
  if (fd < 0) return {};
  char text[128] = {};
  const ssize_t n = ::read(fd, text, sizeof text - 1);
  ::close(fd);
  if (n <= 0) return {};
  // "size resident shared ...", in pages; shared is the file-backed and shared-memory part.
  std::array<std::size_t, 3> pages{};
  const char* p = text;
  for (std::size_t& field : pages) {
    while (*p == ' ') ++p;
    for (; *p >= '0' && *p <= '9'; ++p) field = field * 10 + static_cast<std::size_t>(*p - '0');
  }
  const auto page = static_cast<std::size_t>(::sysconf(_SC_PAGESIZE));
  return {(pages[1] - std::min(pages[1], pages[2])) * page, pages[2] * page};
}

// Open file descriptors, probed one by one (listing /proc/self/fd would allocate), but for the
// snapshot files the writer thread may have open at that moment.
int open_descriptors() {
  int open = 0;
  for (int fd = 0; fd < 4096; ++fd) {
    if (::fcntl(fd, F_GETFD) == -1) continue;
    char link[64];
    char target[4096];
    std::snprintf(link, sizeof link, "/proc/self/fd/%d", fd);
    const ssize_t n = ::readlink(link, target, sizeof target - 1);
    target[n > 0 ? n : 0] = '\0';
    if (std::strstr(target, "/snapshots/") == nullptr) ++open;
  }
  return open;
}

// Watches the run from the frame loop's thread, allocating nothing: the figures at the end of
// the warm-up and at the last pair, and every health message checked against the frame
// summaries before it.
struct Watch final : FrameObserver {
  Steady::time_point warm_after;
  std::atomic<bool>* warmed = nullptr;  // told when the warm-up ends
  bool warm = false;
  std::size_t allocations_warm = 0, allocations_last = 0;
  Resident resident_warm, resident_last;
  std::size_t anonymous_peak = 0;
  int descriptors_warm = 0, descriptors_last = 0;
  std::uint64_t frames = 0, frames_warm = 0;
  std::optional<std::uint32_t> newest;
  std::uint64_t health_checked = 0, health_wrong = 0;
  protocol::Health last_health{};

  void on_frame(const FrameResult&) override {
    ++frames;
    if (!warm && Steady::now() >= warm_after) {
      warm = true;
      frames_warm = frames;
      allocations_warm = test::allocations_in_all_threads();
      resident_warm = resident_bytes();
      descriptors_warm = open_descriptors();
      if (warmed != nullptr) *warmed = true;
    }
    if (!warm) return;
    allocations_last = test::allocations_in_all_threads();
    if (frames % 64 == 0) {
      resident_last = resident_bytes();
      anonymous_peak = std::max(anonymous_peak, resident_last.anonymous);
      descriptors_last = open_descriptors();
    }
  }
  void on_message(const protocol::Message& m) override {
    if (const auto* f = std::get_if<protocol::FrameSummary>(&m)) newest = f->frame;
    const auto* h = std::get_if<protocol::Health>(&m);
    if (h == nullptr || !newest) return;
    ++health_checked;
    const bool adds_up = h->frames + h->dropped == *newest + 1 &&
                         h->dropped == h->dropped_stale + h->dropped_one_side +
                                           h->dropped_both_sides + h->dropped_corrupt;
    health_wrong += adds_up ? 0 : 1;
    last_health = *h;
  }
};

// The robot: reads and decodes everything, and sends a command every 100 ms from a fixed round
// (exposure up and back, stages off and on, a snapshot once the warm-up is over, so that the
// snapshots and their limit fall in the measured part, and one command sent twice).
struct Robot {
  hal::TermiosSerialPort port;
  protocol::FrameDecoder decoder;
  std::atomic<bool> running{true};
  std::atomic<std::uint64_t> acks_ok{0}, acks_rejected{0}, acks_duplicate{0};
  std::atomic<bool> warm{false};
  std::uint16_t sequence = 0;
  protocol::Message last;  // the last command sent

  explicit Robot(const std::string& peer) : port({peer, 115200}) {}

  void send(const protocol::Message& m, std::uint16_t number) {
    last = m;
    std::array<std::uint8_t, protocol::kMaxFrameSize> bytes{};
    const std::size_t n = protocol::encode_frame(m, number, bytes);
    port.write(std::as_bytes(std::span(bytes.data(), n)), 100'000'000);
  }
  void run() {
    std::array<std::byte, 4096> buffer{};
    Steady::time_point next_command = Steady::now();
    int round = 0;
    while (running) {
      const hal::IoResult r = port.read(buffer, 10'000'000);
      for (std::size_t i = 0; r.status == hal::IoStatus::ok && i < r.bytes; ++i) {
        const auto m = decoder.push(static_cast<std::uint8_t>(buffer[i]));
        const auto* ack = m ? std::get_if<protocol::CommandAck>(&m->message) : nullptr;
        if (ack == nullptr) continue;
        if (ack->status == protocol::AckStatus::ok) ++acks_ok;
        if (ack->status == protocol::AckStatus::rejected) ++acks_rejected;
        if (ack->status == protocol::AckStatus::duplicate) ++acks_duplicate;  // never now
      }
      if (Steady::now() < next_command) continue;
      next_command += std::chrono::milliseconds(100);
      const StageMask all = protocol::kAllStages;
      switch (round++ % 6) {
        case 0:
          send(protocol::SetExposure{4000, 300}, sequence++);
          break;
        case 1:
          send(protocol::SetExposure{0, 0}, sequence++);
          break;
        case 2:
          send(protocol::SetStages{static_cast<std::uint16_t>(all & ~0x08)}, sequence++);
          break;
        case 3:
          send(protocol::SetStages{all}, sequence++);
          break;
        case 4:
          if (warm) {
            send(protocol::Snapshot{}, sequence++);
          } else {
            send(protocol::SetStages{all}, sequence++);
          }
          break;
        default:  // the last command again, with its number: its ack was lost, say
          send(last, static_cast<std::uint16_t>(sequence - 1));
          break;
      }
    }
  }
};

TEST(Soak, EveryStageAndFaultsForMinutesWithoutGrowingOrLosingCount) {
  const int seconds = soak_seconds();
  test::SimRig rig(320, 240, 8);
  BoardConfig config = rig.parse(
      "threads: {count: 2}\nsnapshot_directory: snapshots\n"
      "snapshot_limit: 40\n"
      // The outputs' threads too, flat over the run: a recording (one file: the ring's turns
      // are Recording.ALongRecordingIsARingOfWholeFiles') and ROS 2 over DDS on loopback.
      "outputs: {mcap: {directory: recordings, continuous: true, file_mb: 1024, total_mb: 1024,\n"
      "                 min_free_mb: 0},\n"
      "          ros2: {domain: " +
      std::to_string(100 + ::getpid() % 100) + "}}\n");
  config.stages |= protocol::stage_bit(protocol::Stage::sparse);
  rig.add_cascade(config);
  config.serial.backend = "pty";
  config.serial.port.baud = 4'000'000;
  Firmware fw(rig.replaying(config, 3));
  hal::SimFaultRates rates;
  rates.drop = 0.02;
  rates.damaged = 0.005;
  rates.wrong_sequence = 0.005;
  rates.delay = 0.01;
  rates.max_delay = 20'000'000;
  for (const hal::Side side : {hal::Side::left, hal::Side::right}) {
    rates.seed = side == hal::Side::left ? 17 : 71;
    hal::SimCamera& camera = *test::sim_board(fw.board()).camera(side);
    camera.set_fault_rates(rates);
    // One camera lost every 3000 triggers, the sides taking turns.
    for (std::uint32_t at = side == hal::Side::left ? 3000 : 4500; at < 3'000'000; at += 3000) {
      hal::SimFault gone;
      gone.kind = hal::SimFaultKind::disconnect;
      gone.sequence = at;
      camera.inject(gone);
    }
  }
  Robot robot(fw.board().serial_peer());
  Watch watch;
  watch.warmed = &robot.warm;
  watch.warm_after = Steady::now() + std::chrono::seconds(std::max(5, seconds / 10));
  fw.frame_loop().set_observer(&watch);
  std::atomic<bool> stop{false};
  std::thread robot_thread([&] { robot.run(); });
  std::thread timer([&] {
    std::this_thread::sleep_for(std::chrono::seconds(seconds));
    stop = true;
  });
  const RunSummary s = fw.run(0, stop);
  timer.join();
  robot.running = false;
  robot_thread.join();

  const hal::TriggerAccount& t = s.faults.triggers;
  std::printf(
      "soak: %d s, %llu pairs (%llu after the warm-up), %llu health messages; triggers: %llu "
      "published, %llu stale, %llu one side, %llu both sides, %llu corrupt; %llu camera reopens; "
      "resident anonymous %zu KiB at the warm-up, %zu at the end, peak %zu (file-backed %zu, %zu); "
      "%d descriptors; acks %llu ok, "
      "%llu rejected, %llu duplicate\n",
      seconds, static_cast<unsigned long long>(s.frames),
      static_cast<unsigned long long>(s.frames - watch.frames_warm),
      static_cast<unsigned long long>(s.health_messages),
      static_cast<unsigned long long>(t.published), static_cast<unsigned long long>(t.stale),
      static_cast<unsigned long long>(t.one_side), static_cast<unsigned long long>(t.both_sides),
      static_cast<unsigned long long>(t.corrupt),
      static_cast<unsigned long long>(s.faults.camera_reopens),
      watch.resident_warm.anonymous / 1024, watch.resident_last.anonymous / 1024,
      watch.anonymous_peak / 1024, watch.resident_warm.file / 1024, watch.resident_last.file / 1024,
      watch.descriptors_last, static_cast<unsigned long long>(robot.acks_ok.load()),
      static_cast<unsigned long long>(robot.acks_rejected.load()),
      static_cast<unsigned long long>(robot.acks_duplicate.load()));

  ASSERT_TRUE(watch.warm) << "the run ended before its warm-up";
  EXPECT_GT(s.frames - watch.frames_warm, 100u);
  EXPECT_EQ(watch.allocations_last - watch.allocations_warm, 0u)
      << "operator new calls after the warm-up, in any thread";
  EXPECT_LE(watch.anonymous_peak, watch.resident_warm.anonymous + (1u << 20))
      << "anonymous resident memory grew";
  EXPECT_EQ(watch.descriptors_last, watch.descriptors_warm);
  EXPECT_GT(watch.health_checked, 5u);
  EXPECT_EQ(watch.health_wrong, 0u) << "health messages that did not account for every trigger";
  EXPECT_EQ(t.published, s.frames);
  EXPECT_GT(t.one_side, 0u);
  EXPECT_GT(t.corrupt, 0u);
  if (t.published + t.dropped() > 3500) {
    EXPECT_GE(s.faults.camera_reopens, 1u);
  }
  EXPECT_EQ(robot.decoder.stats().bad_crc + robot.decoder.stats().bad_cobs +
                robot.decoder.stats().bad_body + robot.decoder.stats().too_long,
            0u);
  EXPECT_GT(robot.acks_ok.load(), 0u);
  EXPECT_EQ(robot.acks_duplicate.load(), 0u) << "a resend is answered with its first result";
  EXPECT_GT(s.resent_commands, 0u) << "and not applied again";
}

}  // namespace
}  // namespace epipole::firmware
