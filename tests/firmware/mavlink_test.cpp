// MAVLink 2 output: checked byte by byte against the message definitions, with a bit-by-bit
// CRC written independently of the table-free one under test.
#include "epipole/firmware/protocol/mavlink.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>
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

std::vector<std::uint8_t> heartbeat_frame(std::uint8_t sequence) {
  std::vector<std::uint8_t> frame(kMaxFrameSize);
  frame.resize(encode_heartbeat({1, 196}, sequence, frame));
  return frame;
}

std::vector<std::uint8_t> obstacle_frame(std::uint8_t sequence) {
  ObstacleDistance m;
  m.time_usec = 1000u * sequence;
  m.distances_cm.fill(kUnknownDistance);
  for (int i = 0; i < 8; ++i) m.distances_cm[i] = static_cast<std::uint16_t>(100 * i + sequence);
  m.min_distance_cm = 20;
  m.max_distance_cm = 2000;
  m.increment_deg = 11.25f;
  m.angle_offset_deg = -39.375f;
  std::vector<std::uint8_t> frame(kMaxFrameSize);
  frame.resize(encode_obstacle_distance(m, {1, 196}, sequence, frame));
  return frame;
}

// The sequence numbers of the frames the stream decoder delivers from `bytes`, fed one by one,
// as a reader does: next() after each frame, finish() at the end.
std::vector<int> decode_stream(StreamDecoder& decoder, const std::vector<std::uint8_t>& bytes,
                               bool ends = true) {
  std::vector<int> sequences;
  for (const std::uint8_t b : bytes) {
    for (auto frame = decoder.push(b); frame; frame = decoder.next()) {
      sequences.push_back(frame->sequence);
    }
  }
  if (ends) {
    for (auto frame = decoder.finish(); frame; frame = decoder.finish()) {
      sequences.push_back(frame->sequence);
    }
  }
  return sequences;
}

void append(std::vector<std::uint8_t>& to, const std::vector<std::uint8_t>& bytes) {
  to.insert(to.end(), bytes.begin(), bytes.end());
}

TEST(MavlinkStream, DecodesFramesBackToBack) {
  std::vector<std::uint8_t> stream;
  for (int i = 0; i < 6; ++i) {
    append(stream, i % 3 == 0 ? heartbeat_frame(static_cast<std::uint8_t>(i))
                              : obstacle_frame(static_cast<std::uint8_t>(i)));
  }
  StreamDecoder decoder;
  EXPECT_EQ(decode_stream(decoder, stream), (std::vector<int>{0, 1, 2, 3, 4, 5}));
  const StreamStats& s = decoder.stats();
  EXPECT_EQ(s.frames, 6u);
  EXPECT_EQ(s.bad_crc + s.unknown_message + s.bad_flags + s.skipped_bytes + s.lost, 0u);
}

// NAMED_VALUE_FLOAT (id 251, CRC extra 170): time_boot_ms, value, name[10], in that order on the
// wire; trailing zeros of the name dropped.
TEST(Mavlink, NamedValueFloatBytes) {
  std::vector<std::uint8_t> frame(kMaxFrameSize);
  frame.resize(encode_named_value_float("rig_rows", 1.5f, 0x01020304, {7, 196}, 3, frame));
  ASSERT_EQ(frame.size(), 10u + 16u + 2u) << "the name's two trailing zeros dropped";
  const std::vector<std::uint8_t> head{0xFD, 16,  0,   0,   3,   7,   196, 251,  0,
                                       0,    4,   3,   2,   1,   0,   0,   0xC0, 0x3F,  // 1.5f
                                       'r',  'i', 'g', '_', 'r', 'o', 'w', 's'};
  EXPECT_EQ(std::vector<std::uint8_t>(frame.begin(), frame.end() - 2), head);
  const std::uint16_t crc = frame_checksum(frame, 170);
  EXPECT_EQ(frame[frame.size() - 2], crc & 0xFF);
  EXPECT_EQ(frame[frame.size() - 1], crc >> 8);
  const auto parsed = parse_frame(frame);
  ASSERT_TRUE(parsed);
  const auto v = decode_named_value_float(*parsed);
  ASSERT_TRUE(v);
  EXPECT_EQ(v->time_boot_ms, 0x01020304u);
  EXPECT_EQ(v->value, 1.5f);
  EXPECT_STREQ(v->name.data(), "rig_rows");
  EXPECT_FALSE(decode_status_text(*parsed));

  std::vector<std::uint8_t> full(kMaxFrameSize);
  full.resize(encode_named_value_float("rig_cpitch", 0, 0, {7, 196}, 4, full));
  const auto ten = decode_named_value_float(*parse_frame(full));
  ASSERT_TRUE(ten);
  EXPECT_STREQ(ten->name.data(), "rig_cpitch") << "ten characters: no NUL on the wire";
  EXPECT_THROW(encode_named_value_float("eleven_char", 0, 0, {}, 0, full), Error);
}

// STATUSTEXT (id 253, CRC extra 83): severity, text[50], then the extensions id and chunk_seq
// (0: one message); the text's trailing zeros dropped, a longer text cut at 50.
TEST(Mavlink, StatusTextBytes) {
  std::vector<std::uint8_t> frame(kMaxFrameSize);
  frame.resize(encode_status_text(Severity::warning, "hello", {1, 196}, 9, frame));
  const std::vector<std::uint8_t> head{0xFD, 6, 0, 0,   9,   1,   196, 253,
                                       0,    0, 4, 'h', 'e', 'l', 'l', 'o'};
  EXPECT_EQ(std::vector<std::uint8_t>(frame.begin(), frame.end() - 2), head);
  const std::uint16_t crc = frame_checksum(frame, 83);
  EXPECT_EQ(frame[frame.size() - 2], crc & 0xFF);
  EXPECT_EQ(frame[frame.size() - 1], crc >> 8);
  const auto t = decode_status_text(*parse_frame(frame));
  ASSERT_TRUE(t);
  EXPECT_EQ(t->severity, 4);
  EXPECT_STREQ(t->text.data(), "hello");
  EXPECT_EQ(t->id, 0);

  // A chunked text as another sender writes it (the extensions set, 50 characters: no NUL).
  std::vector<std::uint8_t> chunked = {0xFD, 54, 0, 0, 11, 1, 1, 253, 0, 0, 2};
  for (int i = 0; i < 50; ++i) chunked.push_back(static_cast<std::uint8_t>('a' + i % 26));
  chunked.insert(chunked.end(), {0x34, 0x12, 7});
  const std::uint16_t chunked_crc = frame_checksum(
      [&] {
        std::vector<std::uint8_t> with_room = chunked;
        with_room.resize(chunked.size() + 2);
        return with_room;
      }(),
      83);
  chunked.push_back(static_cast<std::uint8_t>(chunked_crc));
  chunked.push_back(static_cast<std::uint8_t>(chunked_crc >> 8));
  const auto c = decode_status_text(*parse_frame(chunked));
  ASSERT_TRUE(c);
  EXPECT_EQ(c->severity, 2);
  EXPECT_EQ(std::string(c->text.data()).size(), 50u);
  EXPECT_EQ(c->text[49], 'a' + 49 % 26);
  EXPECT_EQ(c->id, 0x1234);
  EXPECT_EQ(c->chunk_seq, 7);

  const std::string long_text(60, 'x');
  std::vector<std::uint8_t> cut(kMaxFrameSize);
  cut.resize(encode_status_text(Severity::notice, long_text, {1, 196}, 10, cut));
  EXPECT_EQ(cut.size(), 10u + 51u + 2u)
      << "severity and 50 characters; the zero extensions dropped";
  EXPECT_EQ(std::string(decode_status_text(*parse_frame(cut))->text.data()),
            long_text.substr(0, 50));
}

// ODOMETRY (id 331, CRC extra 91), from common.xml: time_usec u64, x y z, q[4], vx vy vz,
// rollspeed pitchspeed yawspeed, pose_covariance[21], velocity_covariance[21] (floats), frame_id,
// child_frame_id; extensions reset_counter, estimator_type, quality (int8): 233 bytes.
TEST(Mavlink, OdometryLayout) {
  Odometry m;
  m.time_usec = 0x0102030405060708ull;
  m.x = 1.5f;
  m.z = -2.25f;
  m.q = {0.5f, -0.5f, 0.5f, -0.5f};
  m.vx = 0.75f;
  m.yawspeed = -0.125f;
  for (std::size_t i = 0; i < 21; ++i) m.pose_covariance[i] = static_cast<float>(i + 1);
  m.velocity_covariance[0] = std::numeric_limits<float>::quiet_NaN();
  m.reset_counter = 4;
  m.quality = -1;
  std::vector<std::uint8_t> frame(kMaxFrameSize);
  frame.resize(encode_odometry(m, {1, 197}, 5, frame));
  ASSERT_EQ(frame.size(), 10u + 233u + 2u);
  EXPECT_EQ(frame[7] | frame[8] << 8 | frame[9] << 16, 331);
  const std::uint8_t* p = frame.data() + 10;
  EXPECT_EQ(p[0], 0x08);
  EXPECT_EQ(p[7], 0x01);
  EXPECT_EQ(read_float(p + 8), 1.5f);
  EXPECT_EQ(read_float(p + 16), -2.25f);
  EXPECT_EQ(read_float(p + 20), 0.5f);  // q w
  EXPECT_EQ(read_float(p + 24), -0.5f);
  EXPECT_EQ(read_float(p + 36), 0.75f);          // vx
  EXPECT_EQ(read_float(p + 56), -0.125f);        // yawspeed
  EXPECT_EQ(read_float(p + 60), 1.0f);           // pose_covariance[0]
  EXPECT_EQ(read_float(p + 140), 21.0f);         // pose_covariance[20]
  EXPECT_TRUE(std::isnan(read_float(p + 144)));  // velocity_covariance[0]: unknown
  EXPECT_EQ(p[228], kMavFrameLocalFrd);
  EXPECT_EQ(p[229], kMavFrameBodyFrd);
  EXPECT_EQ(p[230], 4);
  EXPECT_EQ(p[231], kMavEstimatorTypeVio);
  EXPECT_EQ(p[232], 0xFF);  // quality -1
  EXPECT_EQ(frame[frame.size() - 2] | frame[frame.size() - 1] << 8, frame_checksum(frame, 91));
  const auto back = decode_odometry(*parse_frame(frame));
  ASSERT_TRUE(back);
  EXPECT_EQ(back->time_usec, m.time_usec);
  EXPECT_EQ(back->q, m.q);
  EXPECT_EQ(back->pose_covariance, m.pose_covariance);
  EXPECT_EQ(back->quality, -1);
  EXPECT_EQ(back->reset_counter, 4);
  EXPECT_FALSE(decode_timesync(*parse_frame(frame)));
}

// TIMESYNC (id 111, CRC extra 34): tc1 i64, ts1 i64; extensions target_system, target_component.
TEST(Mavlink, TimesyncBytes) {
  std::vector<std::uint8_t> frame(kMaxFrameSize);
  frame.resize(encode_timesync({-2, 0x0102030405060708, 3, 4}, {1, 197}, 6, frame));
  ASSERT_EQ(frame.size(), 10u + 18u + 2u);
  const std::vector<std::uint8_t> payload(frame.begin() + 10, frame.end() - 2);
  const std::vector<std::uint8_t> expected{0xFE, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 8,
                                           7,    6,    5,    4,    3,    2,    1,    3,    4};
  EXPECT_EQ(payload, expected);
  EXPECT_EQ(frame[frame.size() - 2] | frame[frame.size() - 1] << 8, frame_checksum(frame, 34));
  // A request from a sender without the extensions: the targets read as 0.
  std::vector<std::uint8_t> request(kMaxFrameSize);
  request.resize(encode_timesync({0, 99, 0, 0}, {1, 1}, 0, request));
  EXPECT_EQ(request[1], 9) << "the zero tail dropped";
  const auto t = decode_timesync(*parse_frame(request));
  ASSERT_TRUE(t);
  EXPECT_EQ(t->tc1, 0);
  EXPECT_EQ(t->ts1, 99);
  EXPECT_EQ(t->target_system, 0);
}

// A sender numbers its frames as they leave: the number changes, the checksum follows.
TEST(Mavlink, SetSequenceMakesTheChecksumAgain) {
  std::vector<std::uint8_t> frame(kMaxFrameSize);
  frame.resize(encode_heartbeat({1, 196}, 0, frame));
  set_sequence(frame, 200);
  const auto parsed = parse_frame(frame);
  ASSERT_TRUE(parsed);
  EXPECT_EQ(parsed->sequence, 200);
  std::vector<std::uint8_t> damaged = frame;
  damaged.pop_back();
  EXPECT_THROW(set_sequence(damaged, 1), Error);
  frame[7] = 99;  // another message
  EXPECT_THROW(set_sequence(frame, 1), Error);
}

TEST(MavlinkStream, DecodesTheMessagesFields) {
  StreamDecoder decoder;
  std::optional<Frame> heartbeat;
  for (const std::uint8_t b : heartbeat_frame(9)) heartbeat = decoder.push(b);
  ASSERT_TRUE(heartbeat);
  const auto h = decode_heartbeat(*heartbeat);
  ASSERT_TRUE(h);
  EXPECT_EQ(h->type, kMavTypeOnboardController);
  EXPECT_EQ(h->autopilot, kMavAutopilotInvalid);
  EXPECT_EQ(h->system_status, kMavStateActive);
  EXPECT_EQ(h->mavlink_version, 3);
  EXPECT_FALSE(decode_obstacle_distance(*heartbeat));

  std::optional<Frame> obstacles;
  for (const std::uint8_t b : obstacle_frame(7)) obstacles = decoder.push(b);
  ASSERT_TRUE(obstacles);
  const auto m = decode_obstacle_distance(*obstacles);
  ASSERT_TRUE(m);
  EXPECT_FALSE(decode_heartbeat(*obstacles));
  EXPECT_EQ(m->time_usec, 7000u);
  EXPECT_EQ(m->distances_cm[0], 7);
  EXPECT_EQ(m->distances_cm[7], 707);
  EXPECT_EQ(m->distances_cm[8], kUnknownDistance);
  EXPECT_EQ(m->min_distance_cm, 20);
  EXPECT_EQ(m->max_distance_cm, 2000);
  EXPECT_EQ(m->increment_deg, 11.25f);
  EXPECT_EQ(m->angle_offset_deg, -39.375f);
  EXPECT_EQ(m->frame, kMavFrameBodyFrd);
}

// Garbage (with start bytes in it), a frame with a flipped bit, a truncated frame and a lost
// one: every undamaged frame is found, and each fault is counted where it belongs.
TEST(MavlinkStream, ResynchronisesAfterDamage) {
  std::vector<std::uint8_t> stream{0x00, 0xFD, 0x13, 0xFD, 0x55};
  append(stream, heartbeat_frame(0));
  auto damaged = obstacle_frame(1);
  damaged[40] ^= 0x10;
  append(stream, damaged);
  append(stream, heartbeat_frame(2));
  const auto whole = obstacle_frame(3);
  stream.insert(stream.end(), whole.begin(), whole.begin() + 60);  // cut short
  append(stream, heartbeat_frame(4));
  append(stream, obstacle_frame(5));
  // 6 is lost on the way
  append(stream, obstacle_frame(7));
  append(stream, heartbeat_frame(8));  // still delivered although the stream ends with it
  StreamDecoder decoder;
  EXPECT_EQ(decode_stream(decoder, stream), (std::vector<int>{0, 2, 4, 5, 7, 8}));
  const StreamStats& s = decoder.stats();
  EXPECT_EQ(s.frames, 6u);
  EXPECT_GE(s.bad_crc, 2u);  // the damaged frame and the truncated one, at least
  EXPECT_EQ(s.lost, 3u);     // 1, 3 and 6
  EXPECT_GE(s.skipped_bytes, 5u + damaged.size() + 60u);
}

// A damaged length byte makes a false start that swallows the frames behind it until it fails:
// they come out with next() at once, and finish() finds what a stream ends with.
TEST(MavlinkStream, FramesHeldBackByAFalseStartAreNotLost) {
  auto false_start = heartbeat_frame(0);
  false_start[1] = 200;  // the length: the candidate takes 212 bytes
  std::vector<std::uint8_t> stream = false_start;
  for (std::uint8_t i = 1; i <= 3; ++i) append(stream, heartbeat_frame(i));
  append(stream, obstacle_frame(4));  // completes the candidate, which fails its checksum
  StreamDecoder decoder;
  std::vector<int> by_push;
  std::vector<int> by_next;
  for (const std::uint8_t b : stream) {
    if (const auto frame = decoder.push(b)) {
      by_push.push_back(frame->sequence);
      for (auto more = decoder.next(); more; more = decoder.next()) {
        by_next.push_back(more->sequence);
      }
    }
  }
  EXPECT_EQ(by_push, (std::vector<int>{1, 4}));
  EXPECT_EQ(by_next, (std::vector<int>{2, 3}));
  EXPECT_EQ(decoder.stats().bad_crc, 1u);
  EXPECT_EQ(decoder.stats().lost, 0u) << "0 was the damaged one, the first of its sender";

  // The same false start at the end of a stream: finish() gives up on it and finds the frame.
  StreamDecoder ending;
  std::vector<std::uint8_t> last = false_start;
  append(last, heartbeat_frame(5));
  EXPECT_TRUE(decode_stream(ending, last, false).empty());
  EXPECT_EQ(ending.buffered(), last.size());
  const auto found = ending.finish();
  ASSERT_TRUE(found);
  EXPECT_EQ(found->sequence, 5);
  EXPECT_FALSE(ending.finish());
  EXPECT_EQ(ending.stats().truncated, 1u);
  EXPECT_EQ(ending.buffered(), 0u);
  EXPECT_EQ(ending.stats().skipped_bytes, false_start.size());
}

// Sequence numbers are each sender's: two senders interleaved lose nothing; one going back has
// restarted.
TEST(MavlinkStream, FollowsEachSendersSequenceNumbers) {
  std::vector<std::uint8_t> stream;
  std::vector<std::uint8_t> frame(kMaxFrameSize);
  for (std::uint8_t i = 0; i < 5; ++i) {
    for (const std::uint8_t system : {std::uint8_t{1}, std::uint8_t{2}}) {
      const std::size_t n =
          encode_heartbeat({system, 196}, static_cast<std::uint8_t>(10 * system + i), frame);
      stream.insert(stream.end(), frame.begin(), frame.begin() + static_cast<std::ptrdiff_t>(n));
    }
  }
  append(stream, heartbeat_frame(0));  // system 1 again from 0: its firmware restarted
  append(stream, heartbeat_frame(3));  // and two frames were lost after that
  StreamDecoder decoder;
  EXPECT_EQ(decode_stream(decoder, stream).size(), 12u);
  EXPECT_EQ(decoder.stats().restarts, 1u);
  EXPECT_EQ(decoder.stats().lost, 2u);
}

TEST(MavlinkStream, CountsUnknownMessagesAndFlags) {
  auto unknown = heartbeat_frame(0);
  unknown[7] = 1;  // SYS_STATUS: no CRC extra known here
  auto flagged = heartbeat_frame(1);
  flagged[2] = 0x02;  // an incompatibility flag this decoder does not know
  std::vector<std::uint8_t> stream;
  append(stream, unknown);
  append(stream, flagged);
  append(stream, heartbeat_frame(2));
  StreamDecoder decoder;
  EXPECT_EQ(decode_stream(decoder, stream), std::vector<int>{2});
  EXPECT_EQ(decoder.stats().unknown_message, 1u);
  EXPECT_EQ(decoder.stats().bad_flags, 1u);
  EXPECT_EQ(decoder.stats().skipped_bytes, unknown.size() + flagged.size());
}

// A signed frame (incompatibility flag 0x01) carries 13 signature bytes after its checksum;
// the signature is skipped, not checked.
TEST(MavlinkStream, SkipsASignature) {
  auto frame = heartbeat_frame(3);
  frame[2] = kIncompatSigned;
  std::vector<std::uint8_t> covered(frame.begin() + 1, frame.end() - 2);
  covered.push_back(kHeartbeatCrcExtra);
  const std::uint16_t crc = crc16_x25(covered);
  frame[frame.size() - 2] = static_cast<std::uint8_t>(crc);
  frame[frame.size() - 1] = static_cast<std::uint8_t>(crc >> 8);
  frame.insert(frame.end(), kSignatureSize, 0xAB);
  append(frame, heartbeat_frame(4));
  StreamDecoder decoder;
  EXPECT_EQ(decode_stream(decoder, frame), (std::vector<int>{3, 4}));
  EXPECT_EQ(decoder.stats().skipped_bytes, 0u);
}

// Random bytes never crash the decoder, and a frame after them is found.
TEST(MavlinkStream, SurvivesRandomBytes) {
  std::mt19937 random(7);
  std::uniform_int_distribution<int> byte(0, 255);
  std::vector<std::uint8_t> stream;
  for (int i = 0; i < 20000; ++i) {
    const int b = byte(random);
    stream.push_back(static_cast<std::uint8_t>(b < 16 ? kStx : b));  // many start bytes
  }
  StreamDecoder decoder;
  const std::size_t garbage_frames = decode_stream(decoder, stream, false).size();
  // A frame is found once the garbage's last candidate has failed: a heartbeat's worth of
  // bytes after it cannot all belong to a false start, so feed a few.
  std::vector<std::uint8_t> tail;
  for (int i = 0; i < 20; ++i) append(tail, heartbeat_frame(static_cast<std::uint8_t>(i)));
  const std::vector<int> found = decode_stream(decoder, tail);
  EXPECT_EQ(garbage_frames, 0u);
  // A false start in the garbage's last 280 bytes can swallow the first heartbeats (its
  // checksum fails only once it is complete); every later one is found, in order.
  ASSERT_GE(found.size(), 7u);
  for (std::size_t i = 1; i < found.size(); ++i) EXPECT_EQ(found[i], found[i - 1] + 1);
  EXPECT_EQ(found.back(), 19);
}

}  // namespace
}  // namespace epipole::mavlink
