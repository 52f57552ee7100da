#include "epipole/firmware/protocol/mavlink.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "epipole/core/bytes.hpp"
#include "epipole/core/error.hpp"

namespace epipole::mavlink {

namespace {

std::optional<std::uint8_t> crc_extra_of(std::uint32_t message_id) {
  if (message_id == kHeartbeatId) return kHeartbeatCrcExtra;
  if (message_id == kObstacleDistanceId) return kObstacleDistanceCrcExtra;
  if (message_id == kNamedValueFloatId) return kNamedValueFloatCrcExtra;
  if (message_id == kStatusTextId) return kStatusTextCrcExtra;
  if (message_id == kOdometryId) return kOdometryCrcExtra;
  if (message_id == kTimesyncId) return kTimesyncCrcExtra;
  return std::nullopt;
}

enum class Check { ok, incomplete, no_start_byte, bad_flags, unknown_message, bad_crc };

std::uint32_t message_id_of(std::span<const std::uint8_t> header) {
  return header[7] | header[8] << 8 | static_cast<std::uint32_t>(header[9]) << 16;
}

// Checks the frame at the start of `bytes`; `size` gets the frame's length (signature
// included) once the header is complete.
Check check_frame(std::span<const std::uint8_t> bytes, std::size_t& size) {
  if (bytes.empty() || bytes[0] != kStx) return Check::no_start_byte;
  if (bytes.size() < kHeaderSize) return Check::incomplete;
  const std::uint8_t flags = bytes[2];
  if ((flags & ~kIncompatSigned) != 0) return Check::bad_flags;
  const std::uint8_t length = bytes[1];
  size = kHeaderSize + length + kChecksumSize + ((flags & kIncompatSigned) ? kSignatureSize : 0);
  if (bytes.size() < size) return Check::incomplete;
  const auto extra = crc_extra_of(message_id_of(bytes));
  if (!extra) return Check::unknown_message;
  std::uint16_t crc = crc16_x25(bytes.subspan(1, kHeaderSize - 1 + length));
  crc = crc16_x25(std::span(&*extra, 1), crc);
  const auto received = static_cast<std::uint16_t>(bytes[kHeaderSize + length] |
                                                   bytes[kHeaderSize + length + 1] << 8);
  return crc == received ? Check::ok : Check::bad_crc;
}

// The frame at the start of `bytes`, which check_frame() found valid and `size` bytes long.
Frame frame_of(std::span<const std::uint8_t> bytes, std::size_t size) {
  Frame frame;
  frame.length = bytes[1];
  frame.sequence = bytes[4];
  frame.system_id = bytes[5];
  frame.component_id = bytes[6];
  frame.message_id = message_id_of(bytes);
  std::memcpy(frame.payload.data(), bytes.data() + kHeaderSize, frame.length);
  frame.wire_size = size;
  return frame;
}

std::uint32_t float_bits(float v) {
  std::uint32_t bits = 0;
  std::memcpy(&bits, &v, sizeof bits);
  return bits;
}

// Wraps a payload (fields in MAVLink wire order) into a frame: MAVLink 2 drops the payload's
// trailing zero bytes (keeping at least one).
std::size_t finish_frame(std::span<const std::uint8_t> payload, std::uint32_t message_id,
                         const Identity& identity, std::uint8_t sequence,
                         std::span<std::uint8_t> out) {
  require(out.size() >= kMaxFrameSize, "mavlink: frame buffer too small");
  std::size_t length = payload.size();
  while (length > 1 && payload[length - 1] == 0) --length;
  out[0] = kStx;
  out[1] = static_cast<std::uint8_t>(length);
  out[2] = 0;  // incompatibility flags: no signing
  out[3] = 0;  // compatibility flags
  out[4] = sequence;
  out[5] = identity.system_id;
  out[6] = identity.component_id;
  out[7] = static_cast<std::uint8_t>(message_id);
  out[8] = static_cast<std::uint8_t>(message_id >> 8);
  out[9] = static_cast<std::uint8_t>(message_id >> 16);
  std::memcpy(out.data() + kHeaderSize, payload.data(), length);
  std::uint16_t crc = crc16_x25(out.subspan(1, kHeaderSize - 1 + length));
  const std::uint8_t extra = *crc_extra_of(message_id);
  crc = crc16_x25(std::span(&extra, 1), crc);
  out[kHeaderSize + length] = static_cast<std::uint8_t>(crc);
  out[kHeaderSize + length + 1] = static_cast<std::uint8_t>(crc >> 8);
  return kHeaderSize + length + kChecksumSize;
}

}  // namespace

std::uint16_t crc16_x25(std::span<const std::uint8_t> bytes, std::uint16_t crc) {
  for (const std::uint8_t b : bytes) {
    std::uint8_t t = static_cast<std::uint8_t>(b ^ (crc & 0xFF));
    t = static_cast<std::uint8_t>(t ^ (t << 4));
    crc = static_cast<std::uint16_t>((crc >> 8) ^ (t << 8) ^ (t << 3) ^ (t >> 4));
  }
  return crc;
}

std::size_t encode_heartbeat(const Identity& identity, std::uint8_t sequence,
                             std::span<std::uint8_t> out, std::uint8_t system_status) {
  std::array<std::uint8_t, 9> payload{};
  ByteWriter w(payload);
  w.u32(0);                         // custom_mode
  w.u8(kMavTypeOnboardController);  // type
  w.u8(kMavAutopilotInvalid);       // autopilot: not a flight controller
  w.u8(0);                          // base_mode
  w.u8(system_status);              // system_status
  w.u8(3);                          // mavlink_version
  return finish_frame(std::span(payload.data(), w.size()), kHeartbeatId, identity, sequence, out);
}

std::size_t encode_obstacle_distance(const ObstacleDistance& m, const Identity& identity,
                                     std::uint8_t sequence, std::span<std::uint8_t> out) {
  std::array<std::uint8_t, 167> payload{};
  ByteWriter w(payload);
  // Base fields sorted by type size, as MAVLink orders them on the wire; then the extensions
  // in their declared order.
  w.u64(m.time_usec);
  for (const std::uint16_t d : m.distances_cm) w.u16(d);
  w.u16(m.min_distance_cm);
  w.u16(m.max_distance_cm);
  w.u8(m.sensor_type);
  w.u8(static_cast<std::uint8_t>(std::clamp(std::lround(m.increment_deg), 0L, 255L)));
  w.u32(float_bits(m.increment_deg));
  w.u32(float_bits(m.angle_offset_deg));
  w.u8(m.frame);
  return finish_frame(std::span(payload.data(), w.size()), kObstacleDistanceId, identity, sequence,
                      out);
}

std::size_t encode_named_value_float(std::string_view name, float value, std::uint32_t time_boot_ms,
                                     const Identity& identity, std::uint8_t sequence,
                                     std::span<std::uint8_t> out) {
  require(name.size() <= kNamedValueNameSize, "mavlink: NAMED_VALUE_FLOAT name \"", name,
          "\" is longer than ", kNamedValueNameSize, " characters");
  std::array<std::uint8_t, 18> payload{};
  ByteWriter w(payload);
  w.u32(time_boot_ms);
  w.f32(value);
  std::memcpy(payload.data() + w.size(), name.data(), name.size());  // the rest stays 0
  return finish_frame(payload, kNamedValueFloatId, identity, sequence, out);
}

std::size_t encode_status_text(Severity severity, std::string_view text, const Identity& identity,
                               std::uint8_t sequence, std::span<std::uint8_t> out) {
  std::array<std::uint8_t, 54> payload{};  // id and chunk_seq (extensions) 0: not chunked
  payload[0] = static_cast<std::uint8_t>(severity);
  std::memcpy(payload.data() + 1, text.data(), std::min(text.size(), kStatusTextSize));
  return finish_frame(payload, kStatusTextId, identity, sequence, out);
}

std::size_t encode_odometry(const Odometry& m, const Identity& identity, std::uint8_t sequence,
                            std::span<std::uint8_t> out) {
  std::array<std::uint8_t, 233> payload{};
  ByteWriter w(payload);
  w.u64(m.time_usec);
  for (const float v : {m.x, m.y, m.z}) w.f32(v);
  for (const float v : m.q) w.f32(v);
  for (const float v : {m.vx, m.vy, m.vz, m.rollspeed, m.pitchspeed, m.yawspeed}) w.f32(v);
  for (const float v : m.pose_covariance) w.f32(v);
  for (const float v : m.velocity_covariance) w.f32(v);
  w.u8(m.frame_id);
  w.u8(m.child_frame_id);
  w.u8(m.reset_counter);  // extensions
  w.u8(m.estimator_type);
  w.u8(static_cast<std::uint8_t>(m.quality));
  return finish_frame(payload, kOdometryId, identity, sequence, out);
}

std::size_t encode_timesync(const Timesync& m, const Identity& identity, std::uint8_t sequence,
                            std::span<std::uint8_t> out) {
  std::array<std::uint8_t, 18> payload{};
  ByteWriter w(payload);
  w.u64(static_cast<std::uint64_t>(m.tc1));
  w.u64(static_cast<std::uint64_t>(m.ts1));
  w.u8(m.target_system);  // extensions
  w.u8(m.target_component);
  return finish_frame(payload, kTimesyncId, identity, sequence, out);
}

ObstacleDistance to_obstacle_distance(const protocol::Obstacles& sectors, std::uint64_t time_usec,
                                      std::uint16_t min_distance_cm,
                                      std::uint16_t max_distance_cm) {
  require(sectors.count >= 1 && sectors.count <= 72, "mavlink: ", int{sectors.count},
          " obstacle sectors (1 to 72 fit OBSTACLE_DISTANCE)");
  require(sectors.field_of_view_centideg > 0, "mavlink: obstacle field of view is 0");
  ObstacleDistance out;
  out.time_usec = time_usec;
  out.min_distance_cm = min_distance_cm;
  out.max_distance_cm = max_distance_cm;
  const float fov = static_cast<float>(sectors.field_of_view_centideg) / 100.0f;
  out.increment_deg = fov / static_cast<float>(sectors.count);
  out.angle_offset_deg = -fov / 2 + out.increment_deg / 2;
  out.distances_cm.fill(kUnknownDistance);
  for (int i = 0; i < sectors.count; ++i) {
    const std::uint16_t mm = sectors.nearest_mm[i];
    if (mm == protocol::kUnknownDepth) continue;
    const long cm = (static_cast<long>(mm) + 5) / 10;
    out.distances_cm[i] = static_cast<std::uint16_t>(
        cm > max_distance_cm ? max_distance_cm + 1 : std::max<long>(cm, min_distance_cm));
  }
  return out;
}

void set_sequence(std::span<std::uint8_t> frame, std::uint8_t sequence) {
  require(frame.size() >= kHeaderSize + kChecksumSize && frame[0] == kStx && frame[2] == 0 &&
              frame.size() == kHeaderSize + frame[1] + kChecksumSize,
          "mavlink: not an unsigned MAVLink 2 frame");
  const auto extra = crc_extra_of(message_id_of(frame));
  require(extra.has_value(), "mavlink: a frame of message ", message_id_of(frame),
          ", which this encoder does not make");
  frame[4] = sequence;
  const std::size_t length = frame[1];
  std::uint16_t crc = crc16_x25(frame.subspan(1, kHeaderSize - 1 + length));
  crc = crc16_x25(std::span(&*extra, 1), crc);
  frame[kHeaderSize + length] = static_cast<std::uint8_t>(crc);
  frame[kHeaderSize + length + 1] = static_cast<std::uint8_t>(crc >> 8);
}

std::optional<Frame> parse_frame(std::span<const std::uint8_t> bytes) {
  std::size_t size = 0;
  if (check_frame(bytes, size) != Check::ok) return std::nullopt;
  return frame_of(bytes, size);
}

std::optional<Heartbeat> decode_heartbeat(const Frame& frame) {
  if (frame.message_id != kHeartbeatId) return std::nullopt;
  ByteReader r(frame.payload);
  Heartbeat h;
  h.custom_mode = r.u32();
  h.type = r.u8();
  h.autopilot = r.u8();
  h.base_mode = r.u8();
  h.system_status = r.u8();
  h.mavlink_version = r.u8();
  return h;
}

std::optional<ObstacleDistance> decode_obstacle_distance(const Frame& frame) {
  if (frame.message_id != kObstacleDistanceId) return std::nullopt;
  ByteReader r(frame.payload);
  ObstacleDistance m;
  m.time_usec = r.u64();
  for (std::uint16_t& d : m.distances_cm) d = r.u16();
  m.min_distance_cm = r.u16();
  m.max_distance_cm = r.u16();
  m.sensor_type = r.u8();
  const std::uint8_t increment = r.u8();
  const float increment_f = r.f32();
  // MAVLink: the float increment (an extension) is used when it is set, else the integer one.
  m.increment_deg = increment_f != 0.0f ? increment_f : static_cast<float>(increment);
  m.angle_offset_deg = r.f32();
  m.frame = r.u8();
  return m;
}

std::optional<NamedValueFloat> decode_named_value_float(const Frame& frame) {
  if (frame.message_id != kNamedValueFloatId) return std::nullopt;
  ByteReader r(frame.payload);
  NamedValueFloat m;
  m.time_boot_ms = r.u32();
  m.value = r.f32();
  std::memcpy(m.name.data(), frame.payload.data() + 8, kNamedValueNameSize);
  return m;
}

std::optional<StatusText> decode_status_text(const Frame& frame) {
  if (frame.message_id != kStatusTextId) return std::nullopt;
  StatusText m;
  m.severity = frame.payload[0];
  std::memcpy(m.text.data(), frame.payload.data() + 1, kStatusTextSize);
  m.id = static_cast<std::uint16_t>(frame.payload[51] | frame.payload[52] << 8);
  m.chunk_seq = frame.payload[53];
  return m;
}

std::optional<Odometry> decode_odometry(const Frame& frame) {
  if (frame.message_id != kOdometryId) return std::nullopt;
  ByteReader r(frame.payload);
  Odometry m;
  m.time_usec = r.u64();
  for (float* v : {&m.x, &m.y, &m.z}) *v = r.f32();
  for (float& v : m.q) v = r.f32();
  for (float* v : {&m.vx, &m.vy, &m.vz, &m.rollspeed, &m.pitchspeed, &m.yawspeed}) *v = r.f32();
  for (float& v : m.pose_covariance) v = r.f32();
  for (float& v : m.velocity_covariance) v = r.f32();
  m.frame_id = r.u8();
  m.child_frame_id = r.u8();
  m.reset_counter = r.u8();
  m.estimator_type = r.u8();
  m.quality = static_cast<std::int8_t>(r.u8());
  return m;
}

std::optional<Timesync> decode_timesync(const Frame& frame) {
  if (frame.message_id != kTimesyncId) return std::nullopt;
  ByteReader r(frame.payload);
  Timesync m;
  m.tc1 = static_cast<std::int64_t>(r.u64());
  m.ts1 = static_cast<std::int64_t>(r.u64());
  m.target_system = r.u8();
  m.target_component = r.u8();
  return m;
}

std::optional<Frame> StreamDecoder::push(std::uint8_t byte) {
  if (size_ == 0 && byte != kStx) {
    ++stats_.skipped_bytes;
    return std::nullopt;
  }
  buffer_[size_++] = byte;
  return next();
}

std::optional<Frame> StreamDecoder::next() {
  while (size_ > 0) {
    std::size_t frame_size = 0;
    const Check check = check_frame(std::span(buffer_.data(), size_), frame_size);
    switch (check) {
      case Check::incomplete:
        return std::nullopt;
      case Check::ok: {
        const Frame frame = frame_of(std::span(buffer_.data(), size_), frame_size);
        drop_front(frame_size);
        note_sequence(frame);
        ++stats_.frames;
        return frame;
      }
      case Check::bad_flags:
        ++stats_.bad_flags;
        break;
      case Check::unknown_message:
        ++stats_.unknown_message;
        break;
      case Check::bad_crc:
        ++stats_.bad_crc;
        break;
      case Check::no_start_byte:  // bytes after a frame that a false start had held back
        break;
    }
    resume_at_next_start_byte();
  }
  return std::nullopt;
}

std::optional<Frame> StreamDecoder::finish() {
  for (;;) {
    if (auto frame = next()) return frame;
    if (size_ == 0) return std::nullopt;
    ++stats_.truncated;  // an incomplete frame is all that is left
    resume_at_next_start_byte();
  }
}

void StreamDecoder::note_sequence(const Frame& frame) {
  for (Sender& s : senders_) {
    if (!s.seen) {
      s = {true, frame.system_id, frame.component_id, frame.sequence};
      return;
    }
    if (s.system_id != frame.system_id || s.component_id != frame.component_id) continue;
    const auto step = static_cast<std::uint8_t>(frame.sequence - s.last_sequence);
    if (step > 128) {
      ++stats_.restarts;  // behind: the sender started counting again
    } else if (step > 0) {
      stats_.lost += step - 1u;
    }
    s.last_sequence = frame.sequence;
    return;
  }
  // More senders than followed: the others' sequence numbers are not checked.
}

// The buffer's first byte began no frame: decoding resumes at the next start byte after it.
void StreamDecoder::resume_at_next_start_byte() {
  std::size_t next = 1;
  while (next < size_ && buffer_[next] != kStx) ++next;
  stats_.skipped_bytes += next;
  drop_front(next);
}

void StreamDecoder::drop_front(std::size_t bytes) {
  std::memmove(buffer_.data(), buffer_.data() + bytes, size_ - bytes);
  size_ -= bytes;
}

}  // namespace epipole::mavlink
