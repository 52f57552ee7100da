#include "epipole/firmware/link.hpp"

#include <algorithm>
#include <chrono>
#include <cstring>

#include "epipole/core/error.hpp"
#include "epipole/firmware/journal.hpp"
#include "epipole/firmware/link_budget.hpp"
#include "epipole/firmware/thread_roles.hpp"
#include "steady_time.hpp"

namespace epipole::firmware {

using detail::steady_now;

namespace {
// One write attempt; commands are read between attempts.
constexpr hal::Nanoseconds kWriteTimeout = 50'000'000;
constexpr hal::Nanoseconds kIdlePoll = 5'000'000;
constexpr std::chrono::milliseconds kFaultPause{50};
std::uint64_t rejected(const protocol::DecoderStats& s) {
  return s.bad_cobs + s.too_long + s.bad_crc + s.bad_version + s.unknown_type + s.bad_body;
}
}  // namespace

Link::Link(hal::SerialPort* port, hal::Clock& clock, LinkConfig config)
    : port_(port),
      clock_(clock),
      config_(config),
      bytes_per_ns_(static_cast<double>(config.baud) / 10.0 * 1e-9),
      tokens_(bytes_per_ns_ * static_cast<double>(config.burst)),
      reserve_(static_cast<double>(essential_reserve_bytes(config.protocol, config.odometry))),
      last_refill_(clock.now()) {
  require(config.baud > 0, "serial link: baud rate ", config.baud, " is not positive");
  require(config.queue_bytes >= 2 * sizeof(encode_buffer_), "serial link: a queue of ",
          config.queue_bytes, " bytes cannot hold two frames");
  require(config.burst > 0, "serial link: the burst must be positive");
  ring_ = std::make_unique<std::uint8_t[]>(config.queue_bytes);
}

Link::~Link() {
  stop(0);
}

void Link::start() {
  if (port_ == nullptr || thread_.joinable()) return;
  stopping_ = false;
  thread_ = std::thread([this] { run(); });
}

void Link::stop(hal::Nanoseconds drain) {
  if (!thread_.joinable()) return;
  drain_deadline_ = steady_now() + drain;
  stopping_ = true;
  thread_.join();
}

bool Link::within_budget(std::size_t bytes, double reserve) {
  const hal::Nanoseconds now = clock_.now();
  const double cap = bytes_per_ns_ * static_cast<double>(config_.burst);
  tokens_ = std::min(cap, tokens_ + bytes_per_ns_ * static_cast<double>(now - last_refill_));
  last_refill_ = now;
  if (static_cast<double>(bytes) + reserve > tokens_) return false;
  tokens_ -= static_cast<double>(bytes);
  return true;
}

bool Link::enqueue(std::span<const std::uint8_t> frame, bool essential) {
  if (port_ == nullptr) return true;
  const std::lock_guard lock(mutex_);
  return enqueue_locked(frame, essential);
}

bool Link::enqueue_locked(std::span<const std::uint8_t> frame, bool essential) {
  const bool fits = within_budget(frame.size(), essential ? 0.0 : reserve_);
  if (!fits || frames_size_ == kMaxFrames || config_.queue_bytes - ring_size_ < frame.size()) {
    ++counters_.messages_dropped;
    if (!fits) ++counters_.over_budget;
    return false;
  }
  std::size_t at = (ring_head_ + ring_size_) % config_.queue_bytes;
  for (const std::uint8_t b : frame) {
    ring_[at] = b;
    at = at + 1 == config_.queue_bytes ? 0 : at + 1;
  }
  ring_size_ += frame.size();
  lengths_[(frames_head_ + frames_size_) % kMaxFrames] = static_cast<std::uint16_t>(frame.size());
  ++frames_size_;
  return true;
}

bool Link::publish(const protocol::Message& message) {
  if (config_.protocol != LinkProtocol::epipole) return false;
  const std::size_t n = protocol::encode_frame(message, sequence_, encode_buffer_);
  ++sequence_;
  return enqueue({encode_buffer_.data(), n}, is_essential(message));
}

template <class Encode>
bool Link::enqueue_mavlink(bool essential, const Encode& encode) {
  if (config_.protocol != LinkProtocol::mavlink) return false;
  const std::size_t n = encode(std::span(encode_buffer_));
  return enqueue({encode_buffer_.data(), n}, essential);
}

bool Link::publish_heartbeat(std::uint8_t system_status) {
  return enqueue_mavlink(true, [&](std::span<std::uint8_t> out) {
    return mavlink::encode_heartbeat(config_.identity, 0, out, system_status);
  });
}

bool Link::publish_obstacle_distance(const mavlink::ObstacleDistance& message) {
  return enqueue_mavlink(true, [&](std::span<std::uint8_t> out) {
    return mavlink::encode_obstacle_distance(message, config_.identity, 0, out);
  });
}

bool Link::publish_odometry(const mavlink::Odometry& message) {
  return enqueue_mavlink(true, [&](std::span<std::uint8_t> out) {
    return mavlink::encode_odometry(message, config_.identity, 0, out);
  });
}

bool Link::publish_named_value(std::string_view name, float value, std::uint32_t time_boot_ms) {
  return enqueue_mavlink(false, [&](std::span<std::uint8_t> out) {
    return mavlink::encode_named_value_float(name, value, time_boot_ms, config_.identity, 0, out);
  });
}

bool Link::publish_status_text(mavlink::Severity severity, std::string_view text) {
  return enqueue_mavlink(true, [&](std::span<std::uint8_t> out) {
    return mavlink::encode_status_text(severity, text, config_.identity, 0, out);
  });
}

bool Link::next_command(Command& out) {
  const std::lock_guard lock(mutex_);
  if (commands_size_ > 0) {
    out = commands_[commands_head_];
    commands_head_ = (commands_head_ + 1) % kMaxCommands;
    --commands_size_;
    return true;
  }
  if (overflowed_size_ > 0) {
    out = Command{overflowed_[overflowed_head_], protocol::Message{}, true};
    overflowed_head_ = (overflowed_head_ + 1) % kMaxCommands;
    --overflowed_size_;
    return true;
  }
  return false;
}

bool Link::alive(hal::Nanoseconds age) const {
  if (!thread_.joinable()) return true;
  return steady_now() - last_round_.load() <= age;
}

LinkCounters Link::counters() const {
  const std::lock_guard lock(mutex_);
  return counters_;
}

// Copies the oldest queued frame out of the ring and writes it whole; false when none waits.
bool Link::write_front() {
  std::size_t length = 0;
  {
    const std::lock_guard lock(mutex_);
    if (frames_size_ == 0) return false;
    length = lengths_[frames_head_];
    for (std::size_t i = 0; i < length; ++i) {
      write_buffer_[i] = ring_[(ring_head_ + i) % config_.queue_bytes];
    }
  }
  if (config_.protocol == LinkProtocol::mavlink) {
    mavlink::set_sequence(std::span(write_buffer_.data(), length), mavlink_sequence_++);
  }
  // A frame given up half written would run into this one at the robot's decoder: end it first.
  if (broken_frame_) {
    const std::byte end{0};
    broken_frame_ = port_->write(std::span(&end, 1), kWriteTimeout).bytes != 1;
  }
  std::size_t written = 0;
  bool ok = true;
  hal::Nanoseconds progress = steady_now();  // when the port last took a byte
  while (written < length) {
    const std::span<const std::byte> rest(
        reinterpret_cast<const std::byte*>(write_buffer_.data()) + written, length - written);
    const hal::IoResult r = port_->write(rest, kWriteTimeout);
    written += r.bytes;
    const hal::Nanoseconds now = steady_now();
    last_round_ = now;
    if (r.bytes > 0) progress = now;
    if (r.status == hal::IoStatus::ok) continue;
    if (r.status != hal::IoStatus::timeout) {
      ok = false;  // the port is gone: the frame with it
      break;
    }
    // The robot is not reading (or the line is slow): its commands are still read, and the
    // frame is given up once the port took nothing for kStuckWrite, or when stopping.
    read_commands(0);
    if (now - progress >= kStuckWrite || (stopping_ && now >= drain_deadline_.load())) {
      ok = false;
      const std::lock_guard lock(mutex_);
      ++counters_.stuck_writes;
      break;
    }
  }
  if (!ok && written > 0) broken_frame_ = true;
  const std::lock_guard lock(mutex_);
  ring_head_ = (ring_head_ + length) % config_.queue_bytes;
  ring_size_ -= length;
  frames_head_ = (frames_head_ + 1) % kMaxFrames;
  --frames_size_;
  if (ok) {
    ++counters_.messages_sent;
  } else {
    ++counters_.messages_dropped;
  }
  counters_.bytes_written += written;
  return true;
}

void Link::read_commands(hal::Nanoseconds timeout) {
  const hal::IoResult r = port_->read(read_buffer_, timeout);
  if (r.status == hal::IoStatus::closed || r.status == hal::IoStatus::hung_up) {
    decoder_.reset();  // whoever is there when it opens again starts afresh
    mavlink_decoder_ = mavlink::StreamDecoder{};
    timesync_request_.reset();
  }
  if (r.status != hal::IoStatus::ok) {
    // A closed port (waiting for its next reopen attempt) returns at once: do not spin.
    if (r.status != hal::IoStatus::timeout && timeout > 0) {
      std::this_thread::sleep_for(std::chrono::nanoseconds(timeout));
    }
    return;
  }
  const std::span<const std::byte> bytes(read_buffer_.data(), r.bytes);
  if (config_.protocol == LinkProtocol::mavlink) {
    take_mavlink_bytes(bytes);
  } else {
    take_bytes(bytes);
  }
}

// TIMESYNC requests (tc1 0) for everyone or for this component; the newest one waiting is
// answered. Every other frame, and an answer to someone else's request, is left alone.
void Link::take_mavlink_bytes(std::span<const std::byte> bytes) {
  const auto note = [&](const mavlink::Frame& frame) {
    const auto request = mavlink::decode_timesync(frame);
    if (!request || request->tc1 != 0) return;
    const mavlink::Identity& me = config_.identity;
    if ((request->target_system != 0 && request->target_system != me.system_id) ||
        (request->target_component != 0 && request->target_component != me.component_id)) {
      return;
    }
    timesync_request_ = mavlink::Timesync{0, request->ts1, frame.system_id, frame.component_id};
  };
  for (const std::byte byte : bytes) {
    for (auto frame = mavlink_decoder_.push(static_cast<std::uint8_t>(byte)); frame;
         frame = mavlink_decoder_.next()) {
      note(*frame);
    }
  }
}

// At the front of the queue, so that the time in it is the time it leaves: the autopilot takes
// half the round trip for the way back.
void Link::answer_timesync() {
  if (!timesync_request_) return;
  mavlink::Timesync answer = *timesync_request_;
  timesync_request_.reset();
  answer.tc1 = clock_.now();
  const std::size_t n =
      mavlink::encode_timesync(answer, config_.identity, 0, std::span(timesync_buffer_));
  const std::lock_guard lock(mutex_);
  if (!within_budget(n, 0.0) || frames_size_ == kMaxFrames ||
      config_.queue_bytes - ring_size_ < n) {
    ++counters_.messages_dropped;
    return;
  }
  ring_head_ = (ring_head_ + config_.queue_bytes - n) % config_.queue_bytes;
  for (std::size_t i = 0; i < n; ++i) {
    ring_[(ring_head_ + i) % config_.queue_bytes] = timesync_buffer_[i];
  }
  ring_size_ += n;
  frames_head_ = (frames_head_ + kMaxFrames - 1) % kMaxFrames;
  lengths_[frames_head_] = static_cast<std::uint16_t>(n);
  ++frames_size_;
  ++counters_.timesync_answers;
}

void Link::take_bytes(std::span<const std::byte> bytes) {
  for (const std::byte byte : bytes) {
    const std::uint64_t rejected_before = rejected(decoder_.stats());
    const auto decoded = decoder_.push(static_cast<std::uint8_t>(byte));
    const std::lock_guard lock(mutex_);
    counters_.rejected_frames += rejected(decoder_.stats()) - rejected_before;
    if (!decoded) continue;
    ++counters_.commands;
    if (commands_size_ == kMaxCommands) {
      // More than the frame loop takes between two pairs: answered "busy" if there is room.
      if (overflowed_size_ == kMaxCommands) {
        ++counters_.rejected_frames;
      } else {
        overflowed_[(overflowed_head_ + overflowed_size_) % kMaxCommands] = decoded->sequence;
        ++overflowed_size_;
      }
      continue;
    }
    commands_[(commands_head_ + commands_size_) % kMaxCommands] = {decoded->sequence,
                                                                   decoded->message, false};
    ++commands_size_;
  }
}

void Link::run() {
  enter_thread_role_or_say(ThreadRole::link);
  bool failed = false;  // in a run of faults, said in the journal at its start
  for (;;) {
    last_round_ = steady_now();
    try {
      answer_timesync();
      const bool wrote = write_front();
      if (stopping_) {
        bool empty = false;
        {
          const std::lock_guard lock(mutex_);
          empty = frames_size_ == 0;
        }
        if (empty || steady_now() >= drain_deadline_.load()) return;
        continue;
      }
      read_commands(wrote ? 0 : kIdlePoll);
      failed = false;
    } catch (const std::exception& e) {
      // The port's recovery can fail in ways it did not foresee (out of memory in a look-up):
      // said once, the frame in hand tried again, and the thread goes on; it never ends the
      // firmware.
      if (!failed && faults_said_.allow(steady_now())) {
        const unsigned long long unsaid = faults_said_.left_out();
        if (unsaid == 0) {
          journal(Priority::error, "serial link: %s; trying again", e.what());
        } else {
          journal(Priority::error, "serial link: %s; trying again (%llu runs of faults not said)",
                  e.what(), unsaid);
        }
      }
      failed = true;
      {
        const std::lock_guard lock(mutex_);
        ++counters_.thread_faults;
      }
      if (stopping_) return;
      std::this_thread::sleep_for(kFaultPause);
    }
  }
}

}  // namespace epipole::firmware
