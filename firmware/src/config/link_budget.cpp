#include "epipole/firmware/link_budget.hpp"

#include <array>
#include <cmath>
#include <variant>

#include "epipole/core/error.hpp"
#include "epipole/firmware/protocol/codec.hpp"
#include "epipole/firmware/protocol/mavlink.hpp"

namespace epipole::firmware {

namespace {

// COBS adds at most one byte in 254 (and one), whatever the content; the frame ends with 0x00.
std::uint64_t epipole_frame_bytes(const protocol::Message& message) {
  std::array<std::uint8_t, protocol::kMaxFrameSize> frame{};
  const std::size_t n = protocol::encode_frame(message, 0, frame);
  return n + n / 254 + 1;
}

// MAVLink 2 trims the payload's trailing zeros: the largest frame has no zero at its end.
std::uint64_t largest_obstacle_distance_bytes() {
  mavlink::ObstacleDistance message;
  message.distances_cm.fill(0xFFFF);
  message.frame = 0xFF;
  std::array<std::uint8_t, mavlink::kMaxFrameSize> frame{};
  return mavlink::encode_obstacle_distance(message, {}, 0, frame);
}

// Every float non-zero, the extensions too.
std::uint64_t largest_odometry_bytes() {
  mavlink::Odometry message;
  message.velocity_covariance.fill(1.0f);
  message.quality = -1;
  std::array<std::uint8_t, mavlink::kMaxFrameSize> frame{};
  return mavlink::encode_odometry(message, {}, 0, frame);
}

std::uint64_t heartbeat_bytes() {
  std::array<std::uint8_t, mavlink::kMaxFrameSize> frame{};
  return mavlink::encode_heartbeat({}, 0, frame);
}

}  // namespace

namespace {

struct Essentials {
  std::uint64_t per_pair = 0;    // largest frame bytes each pair
  std::uint64_t per_second = 0;  // and each second
};

Essentials essentials(LinkProtocol protocol, bool odometry) {
  if (protocol == LinkProtocol::mavlink) {
    return {largest_obstacle_distance_bytes() + (odometry ? largest_odometry_bytes() : 0),
            heartbeat_bytes()};
  }
  return {
      epipole_frame_bytes(protocol::FrameSummary{}) +
          (odometry ? epipole_frame_bytes(protocol::Odometry{}) : 0),
      epipole_frame_bytes(protocol::Health{}) + epipole_frame_bytes(protocol::CalibrationHealth{})};
}

}  // namespace

std::uint64_t essential_bytes_per_second(LinkProtocol protocol, hal::Nanoseconds frame_period,
                                         bool odometry) {
  const Essentials e = essentials(protocol, odometry);
  const double pairs_per_second = 1e9 / static_cast<double>(frame_period);
  return static_cast<std::uint64_t>(std::ceil(pairs_per_second * static_cast<double>(e.per_pair))) +
         e.per_second;
}

bool is_essential(const protocol::Message& message) {
  return std::holds_alternative<protocol::FrameSummary>(message) ||
         std::holds_alternative<protocol::Health>(message) ||
         std::holds_alternative<protocol::CalibrationHealth>(message) ||
         std::holds_alternative<protocol::CommandAck>(message) ||
         std::holds_alternative<protocol::Odometry>(message);
}

std::uint64_t essential_reserve_bytes(LinkProtocol protocol, bool odometry) {
  const Essentials e = essentials(protocol, odometry);
  return e.per_pair + e.per_second;
}

std::string link_capacity_problem(LinkProtocol protocol, int baud, hal::Nanoseconds frame_period,
                                  bool odometry) {
  const std::uint64_t needed = essential_bytes_per_second(protocol, frame_period, odometry);
  const std::uint64_t capacity = link_bytes_per_second(baud);
  if (needed <= capacity) return {};
  return cat(baud, " baud carries ", capacity, " bytes/s, but ",
             protocol == LinkProtocol::mavlink ? "the obstacle distances" : "the pair summaries",
             odometry ? ", the odometry" : "", " and health alone need ", needed, " bytes/s at ",
             1e9 / static_cast<double>(frame_period),
             " pairs/s: raise the baud rate or lower the frame rate");
}

}  // namespace epipole::firmware
