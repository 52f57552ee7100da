#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string_view>
#include <thread>

#include "epipole/firmware/journal.hpp"
#include "epipole/firmware/protocol/codec.hpp"
#include "epipole/firmware/protocol/mavlink.hpp"
#include "epipole/hal/clock.hpp"
#include "epipole/hal/serial_port.hpp"

namespace epipole::firmware {

enum class LinkProtocol { epipole, mavlink };

struct LinkConfig {
  LinkProtocol protocol = LinkProtocol::epipole;
  mavlink::Identity identity;
  // The link's capacity: 8N1 moves baud / 10 bytes a second. Messages that would exceed it are
  // dropped (and counted) rather than queued behind, so the robot always gets fresh data; the
  // larger ones leave a reserve for the summaries, health and acks (link_budget.hpp).
  int baud = 115200;
  hal::Nanoseconds burst = 250'000'000;  // the budget may be saved up for this long
  std::size_t queue_bytes = 16 * 1024;   // encoded frames waiting for the port
  bool odometry = false;  // the odometry is sent every pair (essential, like the summaries)
};

struct LinkCounters {
  std::uint64_t messages_sent = 0;     // written to the port completely
  std::uint64_t messages_dropped = 0;  // over budget, queue full, or lost to a hang-up
  std::uint64_t over_budget = 0;       // of those, more than the baud rate carries
  std::uint64_t bytes_written = 0;
  std::uint64_t commands = 0;          // valid commands received
  std::uint64_t rejected_frames = 0;   // received frames the decoder rejected (and overflows
                                       // that could not even be answered)
  std::uint64_t stuck_writes = 0;      // frames given up because the port took nothing
  std::uint64_t thread_faults = 0;     // exceptions from the port the thread caught and went on
  std::uint64_t timesync_answers = 0;  // MAVLink: the autopilot's TIMESYNC requests answered
};

// A command from the robot, with the sequence number its ack must carry.
struct Command {
  std::uint16_t sequence = 0;
  protocol::Message message;
  bool overflow = false;  // more came at once than the queue holds: not kept (message empty)
};

// The serial link: the frame loop publishes messages (encoded at once into a fixed queue), a
// thread of the link's own writes them to the port whole, and reads and decodes what the robot
// sends into a fixed queue of commands. Everything is allocated by the constructor; publish()
// and next_command() never allocate and never block on the port. A null port (no link) drops
// nothing and sends nothing.
//
// The thread never waits on the port for long: a frame the port takes nothing of for
// kStuckWrite (a robot that stopped reading a USB or pseudo-terminal link) is given up and
// counted, and commands are read between every write attempt, so they are answered within a
// second whatever the robot reads. When the port is closed or hangs up, the decoder starts
// afresh (the robot at the other end may have restarted).
class Link {
 public:
  // The commands the link queues between two turns of the frame loop (more are answered busy).
  static constexpr std::size_t kMaxCommands = 16;
  Link(hal::SerialPort* port, hal::Clock& clock, LinkConfig config);
  ~Link();
  Link(const Link&) = delete;
  Link& operator=(const Link&) = delete;

  void start();
  // Stops the thread after the message being written (and, within `drain`, those queued).
  void stop(hal::Nanoseconds drain = 500'000'000);

  // Frame loop side. Each returns false when the message was dropped.
  bool publish(const protocol::Message& message);
  bool publish_heartbeat(std::uint8_t system_status = mavlink::kMavStateActive);
  bool publish_obstacle_distance(const mavlink::ObstacleDistance& message);
  // A figure a ground station plots (NAMED_VALUE_FLOAT), over the budget's reserve like the
  // native protocol's larger messages; a rare event said (STATUSTEXT), as essential as heartbeats.
  bool publish_named_value(std::string_view name, float value, std::uint32_t time_boot_ms);
  bool publish_status_text(mavlink::Severity severity, std::string_view text);
  // Where the rig is (ODOMETRY), as essential as the obstacles.
  bool publish_odometry(const mavlink::Odometry& message);
  bool next_command(Command& out);
  // The robot's bytes, decoded into the command queue as the link's thread does with what it
  // reads. Only while that thread does not run (a link without a port; the fuzz target).
  void take_bytes(std::span<const std::byte> bytes);

  LinkCounters counters() const;
  // The queue of encoded frames it allocated, and itself (the command queues are in it).
  std::size_t working_set_bytes() const { return config_.queue_bytes + sizeof(Link); }
  LinkProtocol protocol() const { return config_.protocol; }
  // Whether the link's thread went round its loop within `age` (steady clock; true without a
  // thread: no port): the service watchdog is pinged only while it does.
  bool alive(hal::Nanoseconds age) const;
  static constexpr hal::Nanoseconds kStuckWrite = 500'000'000;
  // Epipole frames carry their own sequence numbers; the number of the next one.
  std::uint16_t next_sequence() const { return sequence_; }

 private:
  // An essential message (link_budget.hpp) may take the whole budget; the others leave the
  // reserve for the essential ones.
  bool enqueue(std::span<const std::uint8_t> frame, bool essential);
  bool enqueue_locked(std::span<const std::uint8_t> frame, bool essential);
  // Queues the frame `encode(out)` writes; MAVLink frames are numbered as they go onto the wire
  // (write_front), so one dropped here is no gap in the sequence.
  template <class Encode>
  bool enqueue_mavlink(bool essential, const Encode& encode);
  bool within_budget(std::size_t bytes, double reserve);
  void run();
  bool write_front();
  void read_commands(hal::Nanoseconds timeout);
  // MAVLink input: the autopilot's TIMESYNC requests (nothing else is read).
  void take_mavlink_bytes(std::span<const std::byte> bytes);
  // The last request's answer, at the front of the queue (its time stamped now).
  void answer_timesync();

  hal::SerialPort* port_;
  hal::Clock& clock_;
  LinkConfig config_;
  double bytes_per_ns_;
  double tokens_;
  double reserve_;                            // bytes of budget kept for essential messages
  JournalLimit faults_said_{10'000'000'000};  // runs of the port's exceptions: a line in 10 s
  hal::Nanoseconds last_refill_;
  std::uint16_t sequence_ = 0;
  std::array<std::uint8_t, protocol::kMaxFrameSize + mavlink::kMaxFrameSize> encode_buffer_{};

  // The queue of encoded frames: a byte ring with each frame's length, guarded by mutex_.
  mutable std::mutex mutex_;
  std::unique_ptr<std::uint8_t[]> ring_;
  std::size_t ring_head_ = 0, ring_size_ = 0;
  static constexpr std::size_t kMaxFrames = 256;
  std::array<std::uint16_t, kMaxFrames> lengths_{};
  std::size_t frames_head_ = 0, frames_size_ = 0;
  std::array<Command, kMaxCommands> commands_{};
  std::size_t commands_head_ = 0, commands_size_ = 0;
  // The sequence numbers of commands that came while the queue was full, to be rejected (busy).
  std::array<std::uint16_t, kMaxCommands> overflowed_{};
  std::size_t overflowed_head_ = 0, overflowed_size_ = 0;
  LinkCounters counters_;

  // The link thread's own state.
  std::array<std::uint8_t, protocol::kMaxFrameSize + mavlink::kMaxFrameSize> write_buffer_{};
  std::array<std::byte, 512> read_buffer_{};
  // Replays delivered: the frame loop answers a resend by its content (CommandMemory).
  protocol::FrameDecoder decoder_{true};
  bool broken_frame_ = false;          // the last frame was given up half written
  std::uint8_t mavlink_sequence_ = 0;  // of the next MAVLink frame written
  mavlink::StreamDecoder mavlink_decoder_;
  std::optional<mavlink::Timesync> timesync_request_;  // to answer, with its sender as target
  std::array<std::uint8_t, mavlink::kMaxFrameSize> timesync_buffer_{};
  std::atomic<hal::Nanoseconds> last_round_{0};  // steady time the thread last went round
  std::atomic<bool> stopping_{false};
  std::atomic<hal::Nanoseconds> drain_deadline_{0};
  std::thread thread_;
};

}  // namespace epipole::firmware
