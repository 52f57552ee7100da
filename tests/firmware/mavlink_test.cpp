// MAVLink 2 output: checked byte by byte against the message definitions, with a bit-by-bit
// CRC written independently of the table-free one under test.
#include "epipole/firmware/protocol/mavlink.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "epipole/core/error.hpp"

namespace epipole::mavlink {
namespace {

// CRC-16/MCRF4XX, bit by bit: reflected polynomial 0x8408, initial 0xFFFF, no final XOR.
std::uint16_t reference_crc(const std::vector<std::uint8_t>& bytes) {
  std::uint16_t crc = 0xFFFF;
  for (const std::uint8_t b : bytes) {
    crc ^= b;
    for (int i = 0; i < 8; ++i) crc = (crc & 1) != 0 ? (crc >> 1) ^ 0x8408 : crc >> 1;
  }
  return crc;
}

std::uint16_t frame_checksum(const std::vector<std::uint8_t>& frame, std::uint8_t extra) {
  std::vector<std::uint8_t> covered(frame.begin() + 1, frame.end() - 2);
  covered.push_back(extra);
  return reference_crc(covered);
}

float read_float(const std::uint8_t* p) {
  float v = 0;
  std::memcpy(&v, p, 4);
  return v;
}

TEST(Mavlink, Crc16CheckValue) {
  const std::vector<std::uint8_t> text{'1', '2', '3', '4', '5', '6', '7', '8', '9'};
  EXPECT_EQ(crc16_x25(text), 0x6F91);
  EXPECT_EQ(reference_crc(text), 0x6F91);
}

TEST(Mavlink, HeartbeatBytes) {
  std::vector<std::uint8_t> frame(kMaxFrameSize);
  frame.resize(encode_heartbeat({1, 196}, 42, frame));
  ASSERT_EQ(frame.size(), 21u);
  const std::vector<std::uint8_t> head{0xFD, 9, 0, 0, 42, 1, 196, 0, 0, 0,  // header
                                       0,    0, 0, 0,                       // custom_mode
                                       18,   8, 0, 4, 3};  // type, autopilot, base, status, v3
  EXPECT_EQ(std::vector<std::uint8_t>(frame.begin(), frame.end() - 2), head);
  const std::uint16_t crc = frame_checksum(frame, 50);
  EXPECT_EQ(frame[19], crc & 0xFF);
  EXPECT_EQ(frame[20], crc >> 8);
  const auto parsed = parse_frame(frame);
  ASSERT_TRUE(parsed);
  EXPECT_EQ(parsed->message_id, 0u);
  EXPECT_EQ(parsed->sequence, 42);
}

TEST(Mavlink, ObstacleDistanceLayoutAndTruncation) {
  ObstacleDistance m;
  m.time_usec = 0x0102030405060708ull;
  for (int i = 0; i < 72; ++i) m.distances_cm[i] = static_cast<std::uint16_t>(100 + i);
  m.min_distance_cm = 20;
  m.max_distance_cm = 2000;
  m.increment_deg = 1.25f;
  m.angle_offset_deg = -44.375f;
  m.frame = kMavFrameBodyFrd;
  std::vector<std::uint8_t> frame(kMaxFrameSize);
  frame.resize(encode_obstacle_distance(m, {1, 196}, 7, frame));
  ASSERT_EQ(frame.size(), 10u + 167u + 2u);
  EXPECT_EQ(frame[1], 167);
  EXPECT_EQ(frame[7] | frame[8] << 8, 330);
  const std::uint8_t* p = frame.data() + 10;
  EXPECT_EQ(p[0], 0x08);  // little-endian time_usec
  EXPECT_EQ(p[7], 0x01);
  EXPECT_EQ(p[8] | p[9] << 8, 100);  // distances[0]
  EXPECT_EQ(p[8 + 2 * 71] | p[9 + 2 * 71] << 8, 171);
  EXPECT_EQ(p[152] | p[153] << 8, 20);    // min_distance
  EXPECT_EQ(p[154] | p[155] << 8, 2000);  // max_distance
  EXPECT_EQ(p[156], kMavDistanceSensorUnknown);
  EXPECT_EQ(p[157], 1);                      // increment (integer degrees)
  EXPECT_EQ(read_float(p + 158), 1.25f);     // increment_f
  EXPECT_EQ(read_float(p + 162), -44.375f);  // angle_offset
  EXPECT_EQ(p[166], kMavFrameBodyFrd);
  const std::uint16_t crc = frame_checksum(frame, 23);
  EXPECT_EQ(frame[frame.size() - 2] | frame[frame.size() - 1] << 8, crc);

  // Trailing zero bytes are dropped from the payload, as MAVLink 2 requires.
  m.frame = 0;
  m.angle_offset_deg = 0;
  std::vector<std::uint8_t> shorter(kMaxFrameSize);
  shorter.resize(encode_obstacle_distance(m, {1, 196}, 8, shorter));
  EXPECT_EQ(shorter[1], 162);
  const auto parsed = parse_frame(shorter);
  ASSERT_TRUE(parsed);
  EXPECT_EQ(parsed->payload[166], 0);  // zero-extended
}

TEST(Mavlink, SectorsBecomeCentimetresCentredOnForward) {
  protocol::Obstacles sectors;
  sectors.field_of_view_centideg = 9000;
  sectors.count = 8;
  sectors.nearest_mm = {1234, protocol::kUnknownDepth, 50, 60000, 995, 2000, 3000, 4000};
  const ObstacleDistance m = to_obstacle_distance(sectors, 99, 20, 3000);
  EXPECT_FLOAT_EQ(m.increment_deg, 11.25f);
  EXPECT_FLOAT_EQ(m.angle_offset_deg, -39.375f);
  EXPECT_EQ(m.distances_cm[0], 123);
  EXPECT_EQ(m.distances_cm[1], kUnknownDistance);  // no valid disparity: unknown
  EXPECT_EQ(m.distances_cm[2], 20);                // closer than the minimum: the minimum
  EXPECT_EQ(m.distances_cm[3], 3001);              // beyond the maximum: nothing there
  EXPECT_EQ(m.distances_cm[4], 100);
  for (int i = 8; i < 72; ++i) EXPECT_EQ(m.distances_cm[i], kUnknownDistance) << i;
  sectors.count = 0;
  EXPECT_THROW(to_obstacle_distance(sectors, 0, 20, 3000), Error);
  sectors.count = 4;
  sectors.field_of_view_centideg = 0;
  EXPECT_THROW(to_obstacle_distance(sectors, 0, 20, 3000), Error);
}

TEST(Mavlink, ParserRejectsDamagedAndUnknownFrames) {
  std::vector<std::uint8_t> frame(kMaxFrameSize);
  frame.resize(encode_heartbeat({3, 196}, 1, frame));
  for (std::size_t i = 0; i < frame.size(); ++i) {
    auto damaged = frame;
    damaged[i] ^= 0x01;
    EXPECT_FALSE(parse_frame(damaged)) << i;
  }
  EXPECT_FALSE(parse_frame(std::span(frame.data(), frame.size() - 1)));
  auto other = frame;
  other[7] = 1;  // SYS_STATUS: its CRC extra is not known here
  EXPECT_FALSE(parse_frame(other));
}

}  // namespace
}  // namespace epipole::mavlink
