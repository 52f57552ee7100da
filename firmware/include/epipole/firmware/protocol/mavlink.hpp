#pragma once

// MAVLink 2 output for PX4 and ArduPilot: HEARTBEAT and OBSTACLE_DISTANCE, encoded to the
// common message set's definitions (no generated headers needed for two messages).
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>

#include "epipole/firmware/protocol/messages.hpp"

namespace epipole::mavlink {

inline constexpr std::uint8_t kStx = 0xFD;  // MAVLink 2 start byte
inline constexpr std::size_t kHeaderSize = 10;
inline constexpr std::size_t kChecksumSize = 2;
inline constexpr std::size_t kMaxFrameSize = kHeaderSize + 255 + kChecksumSize;

inline constexpr std::uint32_t kHeartbeatId = 0;
inline constexpr std::uint8_t kHeartbeatCrcExtra = 50;
inline constexpr std::uint32_t kObstacleDistanceId = 330;
inline constexpr std::uint8_t kObstacleDistanceCrcExtra = 23;

inline constexpr std::uint8_t kMavTypeOnboardController = 18;
inline constexpr std::uint8_t kMavAutopilotInvalid = 8;
inline constexpr std::uint8_t kMavStateActive = 4;
inline constexpr std::uint8_t kMavCompIdObstacleAvoidance = 196;
inline constexpr std::uint8_t kMavFrameBodyFrd = 12;
inline constexpr std::uint8_t kMavDistanceSensorUnknown = 4;
inline constexpr std::uint16_t kUnknownDistance = 0xFFFF;

struct Identity {
  std::uint8_t system_id = 1;  // the vehicle's system id
  std::uint8_t component_id = kMavCompIdObstacleAvoidance;
};

struct ObstacleDistance {
  std::uint64_t time_usec = 0;
  std::array<std::uint16_t, 72> distances_cm{};  // kUnknownDistance: not used / unknown
  std::uint16_t min_distance_cm = 0;
  std::uint16_t max_distance_cm = 0;  // max + 1 in a sector: nothing there
  std::uint8_t sensor_type = kMavDistanceSensorUnknown;
  float increment_deg = 0;     // width of one sector
  float angle_offset_deg = 0;  // centre of sector 0 relative to forward, positive clockwise
  std::uint8_t frame = kMavFrameBodyFrd;
};

// CRC-16/MCRF4XX ("X.25" in MAVLink): crc16("123456789") = 0x6F91.
std::uint16_t crc16_x25(std::span<const std::uint8_t> bytes, std::uint16_t crc = 0xFFFF);

// Each returns the frame's size; `out` must hold kMaxFrameSize bytes.
std::size_t encode_heartbeat(const Identity& identity, std::uint8_t sequence,
                             std::span<std::uint8_t> out);
std::size_t encode_obstacle_distance(const ObstacleDistance& message, const Identity& identity,
                                     std::uint8_t sequence, std::span<std::uint8_t> out);

// Epipole's obstacle sectors (millimetres over a horizontal field of view, left to right) as
// OBSTACLE_DISTANCE: the same sectors in centimetres, centred on forward, the rest unused.
// Throws Error for more sectors than MAVLink's 72 or a field of view of 0.
ObstacleDistance to_obstacle_distance(const protocol::Obstacles& sectors, std::uint64_t time_usec,
                                      std::uint16_t min_distance_cm, std::uint16_t max_distance_cm);

// A received MAVLink 2 frame whose checksum matched (for tests and the host tool).
struct Frame {
  std::uint8_t sequence = 0;
  std::uint8_t system_id = 0;
  std::uint8_t component_id = 0;
  std::uint32_t message_id = 0;
  std::array<std::uint8_t, 255> payload{};  // zero-extended past `length`, as receivers do
  std::uint8_t length = 0;
};

// Parses one frame at the start of `bytes` (HEARTBEAT or OBSTACLE_DISTANCE: the checksum needs
// the message's CRC extra); nullopt when it is not a valid, complete frame of those.
std::optional<Frame> parse_frame(std::span<const std::uint8_t> bytes);

}  // namespace epipole::mavlink
