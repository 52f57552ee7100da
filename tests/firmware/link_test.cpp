// The serial link on a real kernel pseudo-terminal: what the frame loop publishes arrives whole
// and in order at the robot's end, the byte budget drops what does not fit, commands come back.
#include "epipole/firmware/link.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <variant>
#include <vector>

#include "epipole/firmware/link_budget.hpp"
#include "pty/pty_serial.hpp"
#include "termios/termios_serial.hpp"

namespace epipole::firmware {
namespace {

using protocol::DecodedMessage;

// The robot's end of the link.
struct Robot {
  hal::TermiosSerialPort port;
  protocol::FrameDecoder decoder;
  explicit Robot(const std::string& peer) : port({peer, 115200}) {}

  // Everything that arrives within `quiet` of silence.
  std::vector<DecodedMessage> receive(hal::Nanoseconds quiet = 300'000'000) {
    std::vector<DecodedMessage> out;
    std::array<std::byte, 1024> buffer{};
    for (;;) {
      const hal::IoResult r = port.read(buffer, quiet);
      if (r.status != hal::IoStatus::ok) return out;
      for (std::size_t i = 0; i < r.bytes; ++i) {
        if (auto m = decoder.push(static_cast<std::uint8_t>(buffer[i]))) out.push_back(*m);
      }
    }
  }
  void send(const protocol::Message& m, std::uint16_t sequence) {
    std::array<std::uint8_t, protocol::kMaxFrameSize> frame{};
    const std::size_t n = protocol::encode_frame(m, sequence, frame);
    ASSERT_EQ(port.write(std::as_bytes(std::span(frame.data(), n)), 1'000'000'000).status,
              hal::IoStatus::ok);
  }
};

protocol::Obstacles obstacles(std::uint32_t frame) {
  protocol::Obstacles o;
  o.frame = frame;
  o.count = 72;
  o.field_of_view_centideg = 9000;
  for (std::size_t i = 0; i < 72; ++i) o.nearest_mm[i] = static_cast<std::uint16_t>(i * 10 + frame);
  return o;
}

TEST(Link, PublishedMessagesArriveWholeAndInOrder) {
  hal::PtySerialPort pty({});
  hal::VirtualClock clock;
  Link link(&pty, clock, {});
  Robot robot(pty.peer_path());
  link.start();
  for (std::uint32_t i = 0; i < 20; ++i) {
    EXPECT_TRUE(link.publish(obstacles(i)));
    clock.advance(50'000'000);  // 20 frames a second: well within 115200 baud
  }
  const auto received = robot.receive();
  link.stop();
  ASSERT_EQ(received.size(), 20u);
  for (std::uint32_t i = 0; i < 20; ++i) {
    EXPECT_EQ(received[i].sequence, i);
    EXPECT_EQ(std::get<protocol::Obstacles>(received[i].message), obstacles(i));
  }
  EXPECT_EQ(robot.decoder.stats().bad_crc + robot.decoder.stats().bad_cobs, 0u);
  const LinkCounters c = link.counters();
  EXPECT_EQ(c.messages_sent, 20u);
  EXPECT_EQ(c.messages_dropped, 0u);
}

std::size_t frame_bytes(const protocol::Message& m) {
  std::array<std::uint8_t, protocol::kMaxFrameSize> frame{};
  return protocol::encode_frame(m, 0, frame);
}

// The larger messages leave a reserve in the budget: the summaries, health and acks go out
// whatever the points and obstacles took.
TEST(Link, DropsWhatExceedsTheByteBudgetButKeepsAReserveForTheEssentials) {
  hal::PtySerialPort pty({});
  hal::VirtualClock clock;
  LinkConfig config;
  config.baud = 19200;  // 1920 bytes a second; a burst of 0.25 s is 480 bytes
  Link link(&pty, clock, config);
  Robot robot(pty.peer_path());
  link.start();
  const std::uint64_t reserve = essential_reserve_bytes(LinkProtocol::epipole);
  const std::uint64_t each = frame_bytes(obstacles(0));
  ASSERT_LT(reserve + each, 480u);
  const std::uint64_t fit = (480 - reserve) / each;  // those that leave the reserve
  std::uint64_t accepted = 0;
  for (std::uint32_t i = 0; i < 10; ++i) accepted += link.publish(obstacles(i)) ? 1 : 0;
  EXPECT_EQ(accepted, fit);
  // What the obstacles left is the essentials' to take.
  EXPECT_TRUE(link.publish(protocol::FrameSummary{}));
  EXPECT_TRUE(link.publish(protocol::Health{}));
  EXPECT_TRUE(link.publish(protocol::CalibrationHealth{}));
  EXPECT_EQ(link.counters().over_budget, 10 - fit);
  clock.advance(1'000'000'000);  // a second later the budget is full again (capped at 480)
  EXPECT_TRUE(link.publish(obstacles(10)));
  const auto received = robot.receive();
  link.stop();
  ASSERT_EQ(received.size(), fit + 4);
  EXPECT_TRUE(std::holds_alternative<protocol::CalibrationHealth>(
      received[static_cast<std::size_t>(fit) + 2].message));
  EXPECT_EQ(std::get<protocol::Obstacles>(received.back().message).frame, 10u);
  EXPECT_EQ(link.counters().messages_dropped, 10 - fit);
}

// What a board file's baud rate must carry: every pair's summary and each second's health at
// their largest (a MAVLink link: obstacle distances and heartbeats), so 9600 baud carries 30
// pairs a second's summaries on neither protocol, and 19200 on the Epipole protocol only.
TEST(LinkBudget, TheEssentialMessagesMustFitTheBaudRate) {
  const hal::Nanoseconds at_30_hz = 33'333'333;
  const std::uint64_t summaries =
      30 * frame_bytes(protocol::FrameSummary{}) + frame_bytes(protocol::Health{});
  EXPECT_GT(essential_bytes_per_second(LinkProtocol::epipole, at_30_hz), summaries);
  EXPECT_NE(link_capacity_problem(LinkProtocol::epipole, 9600, at_30_hz), "");
  EXPECT_EQ(link_capacity_problem(LinkProtocol::epipole, 19200, at_30_hz), "");
  EXPECT_NE(link_capacity_problem(LinkProtocol::mavlink, 19200, at_30_hz), "");
  EXPECT_EQ(link_capacity_problem(LinkProtocol::mavlink, 115200, at_30_hz), "");
  // With the odometry every pair: ODOMETRY beside OBSTACLE_DISTANCE needs 230400 baud at 30 Hz.
  EXPECT_NE(link_capacity_problem(LinkProtocol::mavlink, 115200, at_30_hz, true)
                .find("the obstacle distances, the odometry and health"),
            std::string::npos);
  EXPECT_EQ(link_capacity_problem(LinkProtocol::mavlink, 230400, at_30_hz, true), "");
  EXPECT_EQ(link_capacity_problem(LinkProtocol::epipole, 115200, at_30_hz, true), "");
  EXPECT_EQ(link_capacity_problem(LinkProtocol::epipole, 9600, 200'000'000), "") << "at 5 Hz";
  const std::string problem = link_capacity_problem(LinkProtocol::epipole, 9600, at_30_hz);
  EXPECT_NE(problem.find("9600 baud carries 960 bytes/s"), std::string::npos) << problem;
}

TEST(Link, CommandsFromTheRobotReachTheFrameLoop) {
  hal::PtySerialPort pty({});
  hal::VirtualClock clock;
  Link link(&pty, clock, {});
  Robot robot(pty.peer_path());
  link.start();
  robot.send(protocol::SetStages{0x2B}, 7);
  // Garbage in between is counted and skipped.
  const std::uint8_t garbage[] = {0x13, 0x37, 0x00, 0xFF, 0xFE, 0x00};
  ASSERT_EQ(robot.port.write(std::as_bytes(std::span(garbage)), 1'000'000'000).status,
            hal::IoStatus::ok);
  robot.send(protocol::Snapshot{}, 8);
  std::vector<Command> commands;
  for (int i = 0; i < 200 && commands.size() < 2; ++i) {
    Command c;
    while (link.next_command(c)) commands.push_back(c);
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  link.stop();
  ASSERT_EQ(commands.size(), 2u);
  EXPECT_EQ(commands[0].sequence, 7);
  EXPECT_EQ(std::get<protocol::SetStages>(commands[0].message).enabled_mask, 0x2B);
  EXPECT_EQ(commands[1].sequence, 8);
  EXPECT_TRUE(std::holds_alternative<protocol::Snapshot>(commands[1].message));
  EXPECT_EQ(link.counters().commands, 2u);
  EXPECT_GE(link.counters().rejected_frames, 1u);
}

// A port at whose far end the robot stopped reading: every write times out (after a little of
// its timeout, so that the test runs quickly) having taken nothing; reads return what the test
// queued, as the robot goes on sending.
class StuckPort final : public hal::SerialPort {
 public:
  hal::IoResult read(std::span<std::byte> buffer, hal::Nanoseconds timeout) override {
    {
      const std::lock_guard lock(mutex_);
      if (!incoming_.empty()) {
        const std::size_t n = std::min(buffer.size(), incoming_.size());
        std::copy_n(incoming_.begin(), n, buffer.begin());
        incoming_.erase(incoming_.begin(), incoming_.begin() + static_cast<std::ptrdiff_t>(n));
        return {hal::IoStatus::ok, n};
      }
    }
    std::this_thread::sleep_for(
        std::chrono::nanoseconds(std::min<hal::Nanoseconds>(timeout, 1'000'000)));
    return {hal::IoStatus::timeout, 0};
  }
  hal::IoResult write(std::span<const std::byte>, hal::Nanoseconds timeout) override {
    std::this_thread::sleep_for(std::chrono::nanoseconds(timeout / 10));
    ++writes_;
    return {hal::IoStatus::timeout, 0};
  }
  bool is_open() const override { return true; }
  void reopen() override {}
  void close() override {}

  void receive(const protocol::Message& m, std::uint16_t sequence) {
    std::array<std::uint8_t, protocol::kMaxFrameSize> frame{};
    const std::size_t n = protocol::encode_frame(m, sequence, frame);
    const std::lock_guard lock(mutex_);
    for (std::size_t i = 0; i < n; ++i) incoming_.push_back(static_cast<std::byte>(frame[i]));
  }
  int writes() const { return writes_.load(); }

 private:
  std::mutex mutex_;
  std::vector<std::byte> incoming_;
  std::atomic<int> writes_{0};
};

std::vector<Command> commands_within(Link& link, std::size_t count, hal::Nanoseconds limit) {
  std::vector<Command> out;
  const auto end = std::chrono::steady_clock::now() + std::chrono::nanoseconds(limit);
  while (out.size() < count && std::chrono::steady_clock::now() < end) {
    Command c;
    while (link.next_command(c)) out.push_back(c);
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return out;
}

TEST(Link, ARobotThatStopsReadingDoesNotWedgeTheLink) {
  StuckPort port;
  hal::VirtualClock clock;
  Link link(&port, clock, {});
  link.start();
  for (std::uint32_t i = 0; i < 4; ++i) EXPECT_TRUE(link.publish(obstacles(i)));
  // The robot still sends commands while it reads nothing: they come through within a second.
  port.receive(protocol::SetStages{0x03}, 1);
  const std::vector<Command> first = commands_within(link, 1, 1'000'000'000);
  ASSERT_EQ(first.size(), 1u);
  EXPECT_EQ(first[0].sequence, 1);
  EXPECT_TRUE(link.alive(2 * Link::kStuckWrite)) << "the thread goes round while it writes";
  // Each frame is given up after Link::kStuckWrite without progress, and counted.
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (link.counters().stuck_writes < 2 && std::chrono::steady_clock::now() < end) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  const LinkCounters c = link.counters();
  EXPECT_GE(c.stuck_writes, 2u);
  EXPECT_EQ(c.messages_dropped, c.stuck_writes);
  EXPECT_EQ(c.messages_sent, 0u);
  port.receive(protocol::Snapshot{}, 2);
  EXPECT_EQ(commands_within(link, 1, 1'000'000'000).size(), 1u) << "still reading commands";
  const auto before_stop = std::chrono::steady_clock::now();
  link.stop(0);
  EXPECT_LT(std::chrono::steady_clock::now() - before_stop, std::chrono::seconds(2))
      << "stop() is not held up by the stuck port";
  EXPECT_GT(port.writes(), 2);
}

// A driver that holds the thread in write() whatever the timeout (a kernel bug, a wedged USB
// adapter): the link's thread cannot go round, and alive() says so, so the service watchdog is
// no longer pinged and systemd restarts the firmware.
class HangingPort final : public hal::SerialPort {
 public:
  hal::IoResult read(std::span<std::byte>, hal::Nanoseconds timeout) override {
    std::this_thread::sleep_for(
        std::chrono::nanoseconds(std::min<hal::Nanoseconds>(timeout, 1'000'000)));
    return {hal::IoStatus::timeout, 0};
  }
  hal::IoResult write(std::span<const std::byte> data, hal::Nanoseconds) override {
    std::unique_lock lock(mutex_);
    ++writes_;
    wake_.notify_all();
    wake_.wait(lock, [this] { return released_; });
    return {hal::IoStatus::ok, data.size()};
  }
  bool is_open() const override { return true; }
  void reopen() override {}
  void close() override {}

  void wait_for_a_write() {
    std::unique_lock lock(mutex_);
    wake_.wait(lock, [this] { return writes_ > 0; });
  }
  void release() {
    const std::lock_guard lock(mutex_);
    released_ = true;
    wake_.notify_all();
  }

 private:
  std::mutex mutex_;
  std::condition_variable wake_;
  int writes_ = 0;
  bool released_ = false;
};

// A port whose first calls throw what its recovery did not foresee, then works (a pseudo-terminal).
class ThrowingPort final : public hal::SerialPort {
 public:
  explicit ThrowingPort(int throws) : throws_(throws) {}
  hal::IoResult read(std::span<std::byte> buffer, hal::Nanoseconds timeout) override {
    fault();
    return pty_.read(buffer, timeout);
  }
  hal::IoResult write(std::span<const std::byte> data, hal::Nanoseconds timeout) override {
    fault();
    return pty_.write(data, timeout);
  }
  bool is_open() const override { return pty_.is_open(); }
  void reopen() override { pty_.reopen(); }
  void close() override { pty_.close(); }
  std::string peer_path() const override { return pty_.peer_path(); }

 private:
  void fault() {
    if (throws_.fetch_sub(1) > 0) throw std::runtime_error("the device table is corrupt");
  }
  hal::PtySerialPort pty_{{}};
  std::atomic<int> throws_;
};

TEST(Link, AnExceptionFromThePortNeverEndsTheThread) {
  ThrowingPort port(5);
  hal::VirtualClock clock;
  Link link(&port, clock, {});
  Robot robot(port.peer_path());
  ::testing::internal::CaptureStderr();
  link.start();
  for (std::uint32_t i = 0; i < 3; ++i) EXPECT_TRUE(link.publish(obstacles(i)));
  const auto received = robot.receive(1'000'000'000);
  link.stop();
  const std::string journal = ::testing::internal::GetCapturedStderr();
  ASSERT_EQ(received.size(), 3u) << "each frame tried again after the faults";
  EXPECT_EQ(std::get<protocol::Obstacles>(received[2].message), obstacles(2));
  EXPECT_EQ(link.counters().thread_faults, 5u);
  EXPECT_EQ(link.counters().messages_sent, 3u);
  const std::string line = "serial link: the device table is corrupt; trying again";
  const std::size_t first = journal.find(line);
  ASSERT_NE(first, std::string::npos) << journal;
  EXPECT_EQ(journal.find(line, first + 1), std::string::npos) << "said once: " << journal;
}

TEST(Link, AThreadHeldInThePortIsNotAlive) {
  HangingPort port;
  hal::VirtualClock clock;
  Link link(&port, clock, {});
  EXPECT_TRUE(link.alive(1'000'000)) << "no thread yet: nothing to wait for";
  link.start();
  EXPECT_TRUE(link.publish(obstacles(1)));
  port.wait_for_a_write();
  EXPECT_TRUE(link.alive(1'000'000'000)) << "just went into the write";
  std::this_thread::sleep_for(std::chrono::milliseconds(1200));
  EXPECT_FALSE(link.alive(1'000'000'000)) << "held for 1.2 s";
  port.release();
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(2);
  while (!link.alive(100'000'000) && std::chrono::steady_clock::now() < end) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  EXPECT_TRUE(link.alive(100'000'000)) << "going round again once the port lets go";
  link.stop(0);
}

TEST(Link, CommandsBeyondTheQueueAreKeptToBeAnsweredBusy) {
  StuckPort port;
  hal::VirtualClock clock;
  Link link(&port, clock, {});
  link.start();
  for (std::uint16_t i = 0; i < 20; ++i) port.receive(protocol::SetStages{0x03}, i);
  // Nothing takes commands until all 20 were read.
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(2);
  while (link.counters().commands < 20 && std::chrono::steady_clock::now() < end) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  const std::vector<Command> got = commands_within(link, 20, 1'000'000'000);
  link.stop(0);
  ASSERT_EQ(got.size(), 20u);
  for (std::size_t i = 0; i < got.size(); ++i) {
    EXPECT_EQ(got[i].sequence, i);
    EXPECT_EQ(got[i].overflow, i >= 16) << i;
  }
  EXPECT_EQ(link.counters().rejected_frames, 0u) << "every one answered";
}

TEST(Link, StopFinishesWhatWasQueued) {
  hal::PtySerialPort pty({});
  hal::VirtualClock clock;
  LinkConfig config;
  config.baud = 4'000'000;
  Link link(&pty, clock, config);
  Robot robot(pty.peer_path());
  std::vector<DecodedMessage> received;
  std::thread reader([&] { received = robot.receive(500'000'000); });
  link.start();
  for (std::uint32_t i = 0; i < 60; ++i) ASSERT_TRUE(link.publish(obstacles(i))) << i;
  link.stop();
  reader.join();
  EXPECT_EQ(received.size(), 60u);
  EXPECT_EQ(robot.decoder.stats().bad_cobs + robot.decoder.stats().bad_crc +
                robot.decoder.stats().bad_body,
            0u)
      << "no half-sent frame";
}

TEST(Link, MavlinkModeSendsMavlinkOnly) {
  hal::PtySerialPort pty({});
  hal::VirtualClock clock;
  LinkConfig config;
  config.protocol = LinkProtocol::mavlink;
  Link link(&pty, clock, config);
  Robot robot(pty.peer_path());
  link.start();
  EXPECT_FALSE(link.publish(obstacles(1))) << "no Epipole frames on a MAVLink link";
  EXPECT_TRUE(link.publish_heartbeat());
  mavlink::ObstacleDistance od;
  od.distances_cm.fill(mavlink::kUnknownDistance);
  od.distances_cm[3] = 250;
  od.increment_deg = 5;
  od.max_distance_cm = 2000;
  EXPECT_TRUE(link.publish_obstacle_distance(od));
  std::array<std::uint8_t, 1024> bytes{};
  std::size_t size = 0;
  std::array<std::byte, 512> buffer{};
  for (;;) {
    const hal::IoResult r = robot.port.read(buffer, 300'000'000);
    if (r.status != hal::IoStatus::ok) break;
    for (std::size_t i = 0; i < r.bytes && size < bytes.size(); ++i) {
      bytes[size++] = static_cast<std::uint8_t>(buffer[i]);
    }
  }
  link.stop();
  const auto heartbeat = mavlink::parse_frame(std::span(bytes.data(), size));
  ASSERT_TRUE(heartbeat);
  EXPECT_EQ(heartbeat->message_id, mavlink::kHeartbeatId);
  const std::size_t next = mavlink::kHeaderSize + heartbeat->length + mavlink::kChecksumSize;
  const auto distance = mavlink::parse_frame(std::span(bytes.data() + next, size - next));
  ASSERT_TRUE(distance);
  EXPECT_EQ(distance->message_id, mavlink::kObstacleDistanceId);
  EXPECT_EQ(distance->sequence, heartbeat->sequence + 1);
}

// An autopilot asks for the time (TIMESYNC, tc1 0) while frames wait in the queue: the answer
// goes out before them, with the board's time and the request's ts1, addressed to the asker;
// every frame is numbered as it goes onto the wire. Requests for another system, answers to
// someone else's request and garbage are left alone.
TEST(Link, MavlinkTimesyncRequestsAreAnsweredFirst) {
  hal::PtySerialPort pty({});
  hal::VirtualClock clock;
  clock.advance(123'456'789'000);
  LinkConfig config;
  config.protocol = LinkProtocol::mavlink;
  config.identity = {7, 197};
  Link link(&pty, clock, config);
  Robot robot(pty.peer_path());
  for (int i = 0; i < 8; ++i) EXPECT_TRUE(link.publish_heartbeat());
  const auto send = [&](const mavlink::Timesync& t, std::uint8_t system, std::uint8_t sequence) {
    std::array<std::uint8_t, mavlink::kMaxFrameSize> frame{};
    const std::size_t n = mavlink::encode_timesync(t, {system, 1}, sequence, frame);
    ASSERT_EQ(robot.port.write(std::as_bytes(std::span(frame.data(), n)), 1'000'000'000).status,
              hal::IoStatus::ok);
  };
  const std::array<std::byte, 5> garbage{std::byte{0xFD}, std::byte{3}, std::byte{0},
                                         std::byte{0xFD}, std::byte{0x55}};
  ASSERT_EQ(robot.port.write(garbage, 1'000'000'000).status, hal::IoStatus::ok);
  send({0, 111, 9, 197}, 1, 0);        // for system 9: not ours
  send({5, 222, 7, 197}, 1, 1);        // an answer, not a request
  send({0, 987'654'321, 7, 0}, 1, 2);  // ours (any component)
  // Started with the requests waiting: the first round writes a heartbeat, reads them, and the
  // next answers ahead of the seven heartbeats still queued.
  link.start();
  mavlink::StreamDecoder decoder;
  std::vector<mavlink::Frame> frames;
  std::array<std::byte, 512> buffer{};
  for (;;) {
    const hal::IoResult r = robot.port.read(buffer, 1'500'000'000);
    if (r.status != hal::IoStatus::ok) break;
    for (std::size_t i = 0; i < r.bytes; ++i) {
      for (auto f = decoder.push(static_cast<std::uint8_t>(buffer[i])); f; f = decoder.next()) {
        frames.push_back(*f);
      }
    }
  }
  link.stop();
  ASSERT_EQ(frames.size(), 9u);
  int answers = 0;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    EXPECT_EQ(frames[i].sequence, i) << "numbered in the order written";
    EXPECT_EQ(frames[i].system_id, 7);
    const auto t = mavlink::decode_timesync(frames[i]);
    if (!t) continue;
    ++answers;
    EXPECT_LT(i, 3u) << "ahead of the heartbeats still queued";
    EXPECT_EQ(t->tc1, 123'456'789'000);
    EXPECT_EQ(t->ts1, 987'654'321);
    EXPECT_EQ(t->target_system, 1);
    EXPECT_EQ(t->target_component, 1);
  }
  EXPECT_EQ(answers, 1);
  EXPECT_EQ(link.counters().timesync_answers, 1u);
  EXPECT_EQ(decoder.stats().lost + decoder.stats().bad_crc, 0u);
}

TEST(Link, WithoutAPortNothingIsSent) {
  hal::VirtualClock clock;
  Link link(nullptr, clock, {});
  link.start();
  EXPECT_TRUE(link.publish(obstacles(0)));
  Command c;
  EXPECT_FALSE(link.next_command(c));
  link.stop();
  EXPECT_EQ(link.counters().messages_sent, 0u);
}

}  // namespace
}  // namespace epipole::firmware
