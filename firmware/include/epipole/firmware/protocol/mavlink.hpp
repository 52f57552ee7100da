#pragma once

// MAVLink 2 for PX4 and ArduPilot: HEARTBEAT, OBSTACLE_DISTANCE, NAMED_VALUE_FLOAT, STATUSTEXT,
// ODOMETRY and TIMESYNC, encoded to the common message set's definitions (no generated headers
// needed for six messages).
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

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
inline constexpr std::uint32_t kNamedValueFloatId = 251;
inline constexpr std::uint8_t kNamedValueFloatCrcExtra = 170;
inline constexpr std::uint32_t kStatusTextId = 253;
inline constexpr std::uint8_t kStatusTextCrcExtra = 83;
inline constexpr std::uint32_t kOdometryId = 331;
inline constexpr std::uint8_t kOdometryCrcExtra = 91;
inline constexpr std::uint32_t kTimesyncId = 111;
inline constexpr std::uint8_t kTimesyncCrcExtra = 34;
inline constexpr std::size_t kNamedValueNameSize = 10;  // NAMED_VALUE_FLOAT.name, char[10]
inline constexpr std::size_t kStatusTextSize = 50;      // STATUSTEXT.text, char[50]

inline constexpr std::uint8_t kMavTypeOnboardController = 18;
inline constexpr std::uint8_t kMavAutopilotInvalid = 8;
inline constexpr std::uint8_t kMavStateCalibrating = 2;  // not ready: no calibration yet
inline constexpr std::uint8_t kMavStateActive = 4;
inline constexpr std::uint8_t kMavCompIdObstacleAvoidance = 196;
inline constexpr std::uint8_t kMavFrameBodyFrd = 12;
inline constexpr std::uint8_t kMavFrameLocalFrd = 20;
inline constexpr std::uint8_t kMavEstimatorTypeVio = 3;
inline constexpr std::uint8_t kMavDistanceSensorUnknown = 4;
inline constexpr std::uint16_t kUnknownDistance = 0xFFFF;

// MAV_SEVERITY.
enum class Severity : std::uint8_t {
  emergency = 0,
  alert = 1,
  critical = 2,
  error = 3,
  warning = 4,
  notice = 5,
  info = 6,
  debug = 7,
};

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

// ODOMETRY: the pose of child_frame_id (the vehicle's body) in frame_id, its velocity in the
// child frame and its rates; covariances as the upper triangle of 6x6 row-major matrices
// (x, y, z, roll, pitch, yaw), NaN in the first element: unknown.
struct Odometry {
  std::uint64_t time_usec = 0;
  float x = 0, y = 0, z = 0;
  std::array<float, 4> q{1, 0, 0, 0};  // w, x, y, z
  float vx = 0, vy = 0, vz = 0;
  float rollspeed = 0, pitchspeed = 0, yawspeed = 0;
  std::array<float, 21> pose_covariance{};
  std::array<float, 21> velocity_covariance{};
  std::uint8_t frame_id = kMavFrameLocalFrd;
  std::uint8_t child_frame_id = kMavFrameBodyFrd;
  std::uint8_t reset_counter = 0;
  std::uint8_t estimator_type = kMavEstimatorTypeVio;
  std::int8_t quality = 0;  // 0 unknown, -1 failed, 1..100
};

// TIMESYNC: a request has tc1 0 and ts1 the sender's time (ns); the answer, tc1 the answerer's
// time and ts1 the request's. target_system/component (extensions): the request's sender.
struct Timesync {
  std::int64_t tc1 = 0;
  std::int64_t ts1 = 0;
  std::uint8_t target_system = 0;
  std::uint8_t target_component = 0;
};

// CRC-16/MCRF4XX ("X.25" in MAVLink): crc16("123456789") = 0x6F91.
std::uint16_t crc16_x25(std::span<const std::uint8_t> bytes, std::uint16_t crc = 0xFFFF);

// Each returns the frame's size; `out` must hold kMaxFrameSize bytes.
// NAMED_VALUE_FLOAT: `name` of at most kNamedValueNameSize characters (Error beyond);
// `time_boot_ms` the sender's time since it started.
std::size_t encode_named_value_float(std::string_view name, float value, std::uint32_t time_boot_ms,
                                     const Identity& identity, std::uint8_t sequence,
                                     std::span<std::uint8_t> out);
// STATUSTEXT: `text` cut at kStatusTextSize characters (one message; no chunks).
std::size_t encode_status_text(Severity severity, std::string_view text, const Identity& identity,
                               std::uint8_t sequence, std::span<std::uint8_t> out);
std::size_t encode_odometry(const Odometry& message, const Identity& identity,
                            std::uint8_t sequence, std::span<std::uint8_t> out);
std::size_t encode_timesync(const Timesync& message, const Identity& identity,
                            std::uint8_t sequence, std::span<std::uint8_t> out);
std::size_t encode_heartbeat(const Identity& identity, std::uint8_t sequence,
                             std::span<std::uint8_t> out,
                             std::uint8_t system_status = kMavStateActive);
std::size_t encode_obstacle_distance(const ObstacleDistance& message, const Identity& identity,
                                     std::uint8_t sequence, std::span<std::uint8_t> out);

// Epipole's obstacle sectors (millimetres over a horizontal field of view, left to right) as
// OBSTACLE_DISTANCE: the same sectors in centimetres, centred on forward, the rest unused.
// Throws Error for more sectors than MAVLink's 72 or a field of view of 0.
ObstacleDistance to_obstacle_distance(const protocol::Obstacles& sectors, std::uint64_t time_usec,
                                      std::uint16_t min_distance_cm, std::uint16_t max_distance_cm);

// Gives an encoded frame of the messages above (unsigned) another sequence number, its checksum
// made again: a sender numbers its frames as they go onto the wire.
void set_sequence(std::span<std::uint8_t> frame, std::uint8_t sequence);

// A received MAVLink 2 frame whose checksum matched (for tests and the host tool).
struct Frame {
  std::uint8_t sequence = 0;
  std::uint8_t system_id = 0;
  std::uint8_t component_id = 0;
  std::uint32_t message_id = 0;
  std::array<std::uint8_t, 255> payload{};  // zero-extended past `length`, as receivers do
  std::uint8_t length = 0;
  std::size_t wire_size = 0;  // the frame's bytes: header, payload, checksum (and signature)
};

// Parses one frame at the start of `bytes` (of the six messages above: the checksum needs the
// message's CRC extra); nullopt when it is not a valid, complete frame of those.
std::optional<Frame> parse_frame(std::span<const std::uint8_t> bytes);

inline constexpr std::uint8_t kIncompatSigned = 0x01;  // a 13-byte signature follows the CRC
inline constexpr std::size_t kSignatureSize = 13;

struct Heartbeat {
  std::uint32_t custom_mode = 0;
  std::uint8_t type = 0;
  std::uint8_t autopilot = 0;
  std::uint8_t base_mode = 0;
  std::uint8_t system_status = 0;
  std::uint8_t mavlink_version = 0;
};

struct NamedValueFloat {
  std::uint32_t time_boot_ms = 0;
  float value = 0;
  std::array<char, kNamedValueNameSize + 1> name{};  // NUL-terminated here (not on the wire)
};

struct StatusText {
  std::uint8_t severity = 0;
  std::array<char, kStatusTextSize + 1> text{};  // NUL-terminated here (not on the wire)
  std::uint16_t id = 0;                          // extensions: chunked texts (0: not chunked)
  std::uint8_t chunk_seq = 0;
};

// The fields of a parsed frame of that message; nullopt for a frame of another message.
std::optional<Heartbeat> decode_heartbeat(const Frame& frame);
std::optional<ObstacleDistance> decode_obstacle_distance(const Frame& frame);
std::optional<NamedValueFloat> decode_named_value_float(const Frame& frame);
std::optional<StatusText> decode_status_text(const Frame& frame);
std::optional<Odometry> decode_odometry(const Frame& frame);
std::optional<Timesync> decode_timesync(const Frame& frame);

// What the stream decoder has seen.
struct StreamStats {
  std::uint64_t frames = 0;           // valid frames delivered
  std::uint64_t bad_crc = 0;          // a start byte whose frame's checksum did not match
  std::uint64_t unknown_message = 0;  // a frame of a message this decoder has no CRC extra for
  std::uint64_t bad_flags = 0;        // incompatibility flags other than signing
  std::uint64_t truncated = 0;        // a frame the stream ended in (finish())
  std::uint64_t skipped_bytes = 0;    // bytes outside any valid frame
  std::uint64_t lost = 0;             // sequence numbers a sender skipped (frames lost on the way)
  std::uint64_t restarts = 0;         // a sender's sequence number went back: it restarted
};

// Turns an untrusted byte stream into MAVLink 2 frames of the messages above, as a flight
// controller reads Epipole's output. Fixed memory, never throws: after a frame that does not
// check, decoding resumes at the next start byte inside it, so a damaged frame costs only itself.
// Such a false start can hold back whole frames behind it: after each frame push() returns, call
// next() until it returns none; when the stream ends, finish() until it returns none.
class StreamDecoder {
 public:
  // Feeds one byte; returns a frame when the byte completes a valid one.
  std::optional<Frame> push(std::uint8_t byte);
  // A further frame already complete in what was fed.
  std::optional<Frame> next();
  // The stream has ended: the frame it ended in is counted as truncated, and frames inside it
  // are still found.
  std::optional<Frame> finish();
  const StreamStats& stats() const { return stats_; }
  std::size_t buffered() const { return size_; }  // bytes fed but neither delivered nor skipped

 private:
  // Sequence numbers are followed per sender (system and component); this many senders.
  static constexpr std::size_t kSenders = 8;
  struct Sender {
    bool seen = false;
    std::uint8_t system_id = 0;
    std::uint8_t component_id = 0;
    std::uint8_t last_sequence = 0;
  };

  void note_sequence(const Frame& frame);
  void resume_at_next_start_byte();
  void drop_front(std::size_t bytes);

  std::array<std::uint8_t, kMaxFrameSize + kSignatureSize> buffer_{};
  std::size_t size_ = 0;
  std::array<Sender, kSenders> senders_{};
  StreamStats stats_;
};

}  // namespace epipole::mavlink
