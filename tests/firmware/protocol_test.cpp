// The serial protocol: COBS framing, CRC, every message type, and a decoder that survives
// garbage, truncation, bit errors and replays.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <string>
#include <vector>

#include "epipole/core/crc32.hpp"
#include "epipole/core/error.hpp"
#include "epipole/firmware/protocol/codec.hpp"

namespace epipole::protocol {
namespace {

using Bytes = std::vector<std::uint8_t>;

Bytes cobs(const Bytes& in) {
  Bytes out(cobs_max_encoded_size(in.size()));
  const auto n = cobs_encode(in, out);
  EXPECT_TRUE(n.has_value());
  out.resize(n.value_or(0));
  return out;
}

TEST(Cobs, KnownEncodings) {
  EXPECT_EQ(cobs({0x00}), (Bytes{0x01, 0x01}));
  EXPECT_EQ(cobs({0x00, 0x00}), (Bytes{0x01, 0x01, 0x01}));
  EXPECT_EQ(cobs({0x11, 0x22, 0x00, 0x33}), (Bytes{0x03, 0x11, 0x22, 0x02, 0x33}));
  EXPECT_EQ(cobs({0x11, 0x22, 0x33, 0x44}), (Bytes{0x05, 0x11, 0x22, 0x33, 0x44}));
  EXPECT_EQ(cobs({0x11, 0x00, 0x00, 0x00}), (Bytes{0x02, 0x11, 0x01, 0x01, 0x01}));
  Bytes run(254);
  for (int i = 0; i < 254; ++i) run[i] = static_cast<std::uint8_t>(i + 1);
  Bytes expected{0xFF};
  expected.insert(expected.end(), run.begin(), run.end());
  expected.push_back(0x01);
  EXPECT_EQ(cobs(run), expected);
}

TEST(Cobs, RoundTripsAnyBytesAndNeverEmitsZero) {
  std::mt19937 rng(1);
  for (std::size_t size = 0; size < 700; size += 1 + size / 7) {
    Bytes in(size);
    for (auto& b : in) b = static_cast<std::uint8_t>(rng() % 3 == 0 ? 0 : rng());
    const Bytes encoded = cobs(in);
    EXPECT_EQ(std::count(encoded.begin(), encoded.end(), 0), 0);
    Bytes out(size + 1);
    const auto n = cobs_decode(encoded, out);
    ASSERT_TRUE(n.has_value()) << size;
    out.resize(*n);
    EXPECT_EQ(out, in) << size;
  }
}

TEST(Cobs, RejectsInvalidEncodings) {
  Bytes out(16);
  EXPECT_FALSE(cobs_decode(Bytes{0x05, 0x11, 0x22}, out));        // code runs past the end
  EXPECT_FALSE(cobs_decode(Bytes{0x03, 0x11, 0x00, 0x33}, out));  // a zero inside
  EXPECT_FALSE(cobs_decode(Bytes{0x00}, out));
  Bytes small(2);
  EXPECT_FALSE(cobs_decode(Bytes{0x05, 0x11, 0x22, 0x33, 0x44}, small));
  Bytes tiny(1);
  EXPECT_FALSE(cobs_encode(Bytes{1, 2, 3}, tiny));
}

// One of every message, with non-trivial contents.
std::vector<Message> sample_messages(std::uint32_t seed) {
  std::mt19937 engine(seed);
  const auto rng = [&engine] { return static_cast<std::uint32_t>(engine()); };
  const auto u16 = [&rng] { return static_cast<std::uint16_t>(rng()); };
  Health health;
  health.uptime_ms = rng();
  health.frames = rng();
  health.dropped = rng() % 100;
  health.fps_centi = u16();
  health.latency_p50_us = rng();
  health.latency_p99_us = rng();
  for (auto& s : health.stage_us) s = rng();
  health.dropped_stale = rng();
  health.dropped_one_side = rng();
  health.dropped_both_sides = rng();
  health.dropped_corrupt = rng();
  health.camera_timeouts = rng();
  health.camera_reopens = rng();
  health.trigger_losses = rng();
  health.link_reopens = rng();
  health.unpaired_frames = rng();
  health.bad_commands = rng();
  health.messages_dropped = rng();
  health.snapshot_failures = rng();
  health.flags = u16();
  health.wait_p50_us = rng();
  health.wait_p99_us = rng();
  health.busy_permille = u16();
  health.trigger_bounces = rng();
  health.pairs_off_trigger = rng();
  FrameSummary summary{rng(), (std::uint64_t{rng()} << 32) | rng(), rng(), u16(), u16(), 999, 3,
                       u16()};
  Detections detections;
  detections.frame = rng();
  detections.count = kMaxDetections;
  for (auto& d : detections.items) d = {u16(), u16(), u16(), u16(), 7, u16()};
  Obstacles obstacles;
  obstacles.frame = rng();
  obstacles.field_of_view_centideg = 9000;
  obstacles.count = kMaxSectors;
  for (auto& n : obstacles.nearest_mm) n = u16();
  DepthGrid grid;
  grid.frame = rng();
  grid.field_of_view_centideg = 7732;
  grid.vertical_field_of_view_centideg = 5129;
  grid.columns = 16;
  grid.count = kMaxGridCells;
  for (auto& n : grid.nearest_mm) n = u16();
  Points points;
  points.frame = rng();
  points.count = 5;
  for (int i = 0; i < 5; ++i) {
    points.items[i] = {u16(), u16(), static_cast<std::int32_t>(rng()),
                       -static_cast<std::int32_t>(rng() % 1000), static_cast<std::int32_t>(rng())};
  }
  Odometry odometry;
  odometry.frame = rng();
  odometry.trigger_ns = (std::uint64_t{rng()} << 32) | rng();
  odometry.status = OdometryStatus::lost;
  odometry.reset_counter = 3;
  odometry.quality = 77;
  odometry.x_mm = -static_cast<std::int32_t>(rng() % 100000);
  odometry.z_mm = static_cast<std::int32_t>(rng() % 100000);
  odometry.qw_e9 = 707106781;
  odometry.qy_e9 = -707106781;
  odometry.vx_mm_s = -1234;
  odometry.wz_mrad_s = -5678;
  odometry.sz_mm = 65535;
  odometry.srx_cdeg = 12;
  odometry.features = 900;
  odometry.tracked = 800;
  odometry.inliers = 700;
  odometry.keyframes = rng();
  return {health,
          summary,
          odometry,
          detections,
          obstacles,
          points,
          CalibrationHealth{12, -34, 56, kDriftEstimated, 30, 300, -200, 2, 44},
          CommandAck{4242, AckStatus::rejected, AckReason::timing},
          SetTriggerRate{30'000},
          SetExposure{5000, 120},
          SetStages{0x3F},
          Snapshot{},
          Recalibrate{},
          SaveCalibration{},
          grid,
          Ground{rng(), kGroundFound, u16(), -1234, static_cast<std::int16_t>(-32768), u16()}};
}

Bytes frame_of(const Message& message, std::uint16_t sequence) {
  Bytes out(kMaxFrameSize);
  out.resize(encode_frame(message, sequence, out));
  return out;
}

std::vector<DecodedMessage> decode_all(FrameDecoder& decoder, const Bytes& stream) {
  std::vector<DecodedMessage> out;
  for (const std::uint8_t b : stream) {
    if (auto m = decoder.push(b)) out.push_back(std::move(*m));
  }
  return out;
}

TEST(Protocol, EveryMessageRoundTrips) {
  const auto messages = sample_messages(3);
  Bytes stream;
  for (std::size_t i = 0; i < messages.size(); ++i) {
    const Bytes frame = frame_of(messages[i], static_cast<std::uint16_t>(100 + i));
    EXPECT_LE(frame.size(), kMaxFrameSize);
    EXPECT_EQ(frame.back(), 0);
    EXPECT_EQ(std::count(frame.begin(), frame.end() - 1, 0), 0);
    stream.insert(stream.end(), frame.begin(), frame.end());
  }
  FrameDecoder decoder;
  const auto decoded = decode_all(decoder, stream);
  ASSERT_EQ(decoded.size(), messages.size());
  for (std::size_t i = 0; i < messages.size(); ++i) {
    EXPECT_EQ(decoded[i].sequence, 100 + i);
    EXPECT_EQ(decoded[i].message, messages[i]) << name_of(type_of(messages[i]));
  }
  EXPECT_EQ(decoder.stats().frames, messages.size());
  EXPECT_EQ(decoder.stats().lost, 0u);
}

TEST(Protocol, SurvivesGarbageBetweenFrames) {
  const auto messages = sample_messages(4);
  std::mt19937 rng(9);
  Bytes stream;
  for (std::size_t i = 0; i < messages.size(); ++i) {
    for (int k = 0; k < 40; ++k) stream.push_back(static_cast<std::uint8_t>(rng()));
    stream.push_back(0);  // garbage ends somewhere; the next frame starts clean
    const Bytes frame = frame_of(messages[i], static_cast<std::uint16_t>(i));
    stream.insert(stream.end(), frame.begin(), frame.end());
  }
  FrameDecoder decoder;
  const auto decoded = decode_all(decoder, stream);
  ASSERT_EQ(decoded.size(), messages.size());
  for (std::size_t i = 0; i < messages.size(); ++i) EXPECT_EQ(decoded[i].message, messages[i]);
  const auto& s = decoder.stats();
  EXPECT_GT(s.bad_cobs + s.bad_crc + s.empty + s.bad_body, 0u);
}

TEST(Protocol, ATruncatedFrameCostsOnlyItselfAndItsSuccessor) {
  const auto messages = sample_messages(5);
  const Bytes first = frame_of(messages[1], 1);
  Bytes stream(first.begin(), first.begin() + static_cast<std::ptrdiff_t>(first.size() / 2));
  for (std::uint16_t seq = 2; seq < 6; ++seq) {
    const Bytes frame = frame_of(messages[seq], seq);
    stream.insert(stream.end(), frame.begin(), frame.end());
  }
  FrameDecoder decoder;
  const auto decoded = decode_all(decoder, stream);
  // The half frame merges with frame 2 into one bad frame; 3, 4, 5 arrive.
  ASSERT_EQ(decoded.size(), 3u);
  EXPECT_EQ(decoded[0].sequence, 3);
  EXPECT_EQ(decoded[0].message, messages[3]);
}

TEST(Protocol, EverySingleBitErrorIsRejected) {
  const auto messages = sample_messages(6);
  for (const Message& message : messages) {
    const Bytes frame = frame_of(message, 77);
    for (std::size_t bit = 0; bit < 8 * (frame.size() - 1); ++bit) {
      Bytes damaged = frame;
      damaged[bit / 8] ^= static_cast<std::uint8_t>(1u << (bit % 8));
      FrameDecoder decoder;
      EXPECT_TRUE(decode_all(decoder, damaged).empty())
          << name_of(type_of(message)) << " bit " << bit;
    }
  }
}

TEST(Protocol, ReplaysAreDroppedAndLossesCounted) {
  const Message m = SetStages{1};
  FrameDecoder decoder;
  Bytes stream;
  for (const int seq : {10, 11, 11, 9, 14, 15, 2000, 2001}) {
    const Bytes f = frame_of(m, static_cast<std::uint16_t>(seq));
    stream.insert(stream.end(), f.begin(), f.end());
  }
  const auto decoded = decode_all(decoder, stream);
  std::vector<std::uint16_t> sequences;
  for (const auto& d : decoded) sequences.push_back(d.sequence);
  // 11 again is a replay; 9 was never delivered: late, delivered; 12, 13 lost; 2000 is far
  // ahead: 1984 lost.
  EXPECT_EQ(sequences, (std::vector<std::uint16_t>{10, 11, 9, 14, 15, 2000, 2001}));
  EXPECT_EQ(decoder.stats().replays, 1u);
  EXPECT_EQ(decoder.stats().lost, 2u + 1984u);

  // A sender that restarts from 0 after 2001 is resynchronised, not taken for a replay.
  const Bytes restart = frame_of(m, 0);
  EXPECT_EQ(decode_all(decoder, restart).size(), 1u);
  EXPECT_EQ(decoder.stats().resyncs, 1u);
}

TEST(Protocol, ASenderThatRestartsFromZeroIsHeardAtOnce) {
  // A robot that rebooted after command 20 starts again at 0: 0 is never a replay, and 1, 2
  // follow it (before the rule, 0..19 were all taken for replays and dropped unanswered).
  const Message m = SetStages{1};
  FrameDecoder decoder;
  Bytes stream;
  for (const int seq : {18, 19, 20, 0, 1, 2}) {
    const Bytes f = frame_of(m, static_cast<std::uint16_t>(seq));
    stream.insert(stream.end(), f.begin(), f.end());
  }
  std::vector<std::uint16_t> sequences;
  for (const auto& d : decode_all(decoder, stream)) sequences.push_back(d.sequence);
  EXPECT_EQ(sequences, (std::vector<std::uint16_t>{18, 19, 20, 0, 1, 2}));
  EXPECT_EQ(decoder.stats().resyncs, 1u);
  EXPECT_EQ(decoder.stats().replays, 0u);
  EXPECT_EQ(decoder.stats().lost, 0u);

  // 0 right after 65535 is the count wrapping, not a restart.
  FrameDecoder wrapping;
  Bytes wrap;
  for (const int seq : {65534, 65535, 0, 1}) {
    const Bytes f = frame_of(m, static_cast<std::uint16_t>(seq));
    wrap.insert(wrap.end(), f.begin(), f.end());
  }
  EXPECT_EQ(decode_all(wrapping, wrap).size(), 4u);
  EXPECT_EQ(wrapping.stats().resyncs + wrapping.stats().replays + wrapping.stats().lost, 0u);
}

TEST(Protocol, AFrameLostAndSentAgainIsDeliveredNotTakenForAReplay) {
  // The robot's command 11 was damaged on the way; 12 came; the robot sends 11 again (no ack):
  // it is new to the firmware, and applied. Sent once more, it is a replay.
  const Message m = SetStages{1};
  FrameDecoder decoder(true);
  Bytes stream;
  for (const int seq : {10, 12, 11, 11}) {
    const Bytes f = frame_of(m, static_cast<std::uint16_t>(seq));
    stream.insert(stream.end(), f.begin(), f.end());
  }
  const auto decoded = decode_all(decoder, stream);
  ASSERT_EQ(decoded.size(), 4u);
  EXPECT_EQ(decoded[2].sequence, 11);
  EXPECT_FALSE(decoded[2].replay);
  EXPECT_TRUE(decoded[3].replay);
  EXPECT_EQ(decoder.stats().lost, 0u) << "11 was counted lost, then came";
  EXPECT_EQ(decoder.stats().replays, 1u);
  // A robot that sends its first command, 0, twice (the ack was lost): the second is a replay.
  FrameDecoder zero(true);
  Bytes twice = frame_of(m, 0);
  const Bytes again = frame_of(m, 0);
  twice.insert(twice.end(), again.begin(), again.end());
  const auto zeros = decode_all(zero, twice);
  ASSERT_EQ(zeros.size(), 2u);
  EXPECT_TRUE(zeros[1].replay);
  EXPECT_EQ(zero.stats().resyncs, 0u);
}

TEST(Protocol, ReplaysCanBeDeliveredFlaggedAndADecoderReset) {
  const Message m = SetStages{1};
  FrameDecoder decoder(true);  // as the link reads commands: a command sent again is answered
  Bytes stream;
  for (const int seq : {5, 6, 6, 5}) {
    const Bytes f = frame_of(m, static_cast<std::uint16_t>(seq));
    stream.insert(stream.end(), f.begin(), f.end());
  }
  const Bytes half = frame_of(m, 7);
  stream.insert(stream.end(), half.begin(), half.begin() + 5);  // the link drops mid-frame
  const auto decoded = decode_all(decoder, stream);
  ASSERT_EQ(decoded.size(), 4u);
  EXPECT_FALSE(decoded[0].replay);
  EXPECT_FALSE(decoded[1].replay);
  EXPECT_TRUE(decoded[2].replay);
  EXPECT_TRUE(decoded[3].replay);
  EXPECT_EQ(decoder.stats().replays, 2u);
  // The link reopened: the half frame is forgotten, and 3 (behind 6) is new, not a replay.
  decoder.reset();
  const auto after = decode_all(decoder, frame_of(m, 3));
  ASSERT_EQ(after.size(), 1u);
  EXPECT_FALSE(after[0].replay);
  EXPECT_EQ(decoder.stats().bad_cobs + decoder.stats().bad_crc + decoder.stats().bad_body, 0u);
}

TEST(Protocol, OverlongAndUnknownFramesAreCounted) {
  FrameDecoder decoder;
  Bytes stream(5000, 0x42);
  stream.push_back(0);
  const Bytes good = frame_of(Snapshot{}, 1);
  stream.insert(stream.end(), good.begin(), good.end());
  EXPECT_EQ(decode_all(decoder, stream).size(), 1u);
  EXPECT_EQ(decoder.stats().too_long, 1u);

  // A well-formed frame of an unknown type, one of a future version and one of version 1 (no
  // flags in health and frame yet).
  for (const auto& [version, type] :
       {std::pair<int, int>{kVersion, 0x55}, std::pair<int, int>{kVersion + 1, 0x01},
        std::pair<int, int>{1, 0x01}}) {
    Bytes payload{static_cast<std::uint8_t>(version), static_cast<std::uint8_t>(type), 5, 0};
    const std::uint32_t c = crc32(payload);
    for (int i = 0; i < 4; ++i) payload.push_back(static_cast<std::uint8_t>(c >> (8 * i)));
    Bytes frame = cobs(payload);
    frame.push_back(0);
    EXPECT_TRUE(decode_all(decoder, frame).empty());
  }
  EXPECT_EQ(decoder.stats().unknown_type, 1u);
  EXPECT_EQ(decoder.stats().bad_version, 2u);
}

// Where docs/protocol.md puts them: health's flags (u16) after its counters, then (version 4)
// its occupancy, then (version 5) its trigger glitches, then (version 6) the outputs'
// drops and failures; the frame's flags (u8) last.
TEST(Protocol, HealthsFlagsAndOccupancyAndTheFramesFlagsAreWhereTheDocumentSays) {
  const auto payload_of = [](const Message& m) {
    const Bytes frame = frame_of(m, 0);
    Bytes payload(kMaxPayloadSize);
    const auto n = cobs_decode(std::span(frame.data(), frame.size() - 1), payload);
    EXPECT_TRUE(n.has_value());
    payload.resize(n.value_or(0));
    return payload;
  };
  Health health;
  health.flags = 0xA501;
  health.wait_p50_us = 0x04030201;
  health.wait_p99_us = 0x08070605;
  health.busy_permille = 0x03E8;
  health.trigger_bounces = 0x0C0B0A09;
  health.pairs_off_trigger = 0x100F0E0D;
  health.outputs_dropped = 0x14131211;
  health.output_failures = 0x18171615;
  const Bytes h = payload_of(health);
  // 3 x u32, u16, 2 x u32, 10 x u32 stage times, 4 x u32 dropped by cause, 8 x u32 counters,
  // u16 flags, 2 x u32 waits, u16 busy, 2 x u32 trigger glitches, 2 x u32 outputs.
  ASSERT_EQ(h.size(), kHeaderSize + 138 + kCrcSize);
  EXPECT_EQ(h[0], 9) << "version";
  EXPECT_EQ(h[kHeaderSize + 110], 0x01);
  EXPECT_EQ(h[kHeaderSize + 111], 0xA5);
  for (int i = 0; i < 8; ++i) EXPECT_EQ(h[kHeaderSize + 112 + i], i + 1) << i;
  EXPECT_EQ(h[kHeaderSize + 120], 0xE8);
  EXPECT_EQ(h[kHeaderSize + 121], 0x03);
  for (int i = 0; i < 16; ++i) EXPECT_EQ(h[kHeaderSize + 122 + i], i + 9) << i;
  FrameSummary frame;
  frame.flags = kFrameTriggerFromCapture;
  const Bytes f = payload_of(frame);
  ASSERT_EQ(f.size(), kHeaderSize + 26 + kCrcSize);
  EXPECT_EQ(f[kHeaderSize + 25], kFrameTriggerFromCapture);
}

// docs/protocol.md's table: the odometry's fields in order, little-endian, 89 bytes.
TEST(Protocol, TheOdometryIsWhereTheDocumentSays) {
  Odometry m;
  m.frame = 0x04030201;
  m.trigger_ns = 0x0C0B0A0908070605;
  m.status = OdometryStatus::tracking;
  m.reset_counter = 2;
  m.quality = 100;
  m.x_mm = -2;
  m.qw_e9 = 1'000'000'000;
  m.keyframes = 0x44434241;
  Bytes payload(kMaxPayloadSize);
  const Bytes frame = frame_of(m, 0);
  const auto n = cobs_decode(std::span(frame.data(), frame.size() - 1), payload);
  ASSERT_TRUE(n.has_value());
  payload.resize(*n);
  ASSERT_EQ(payload.size(), kHeaderSize + 89 + kCrcSize);
  const auto at = [&](std::size_t i) { return payload[kHeaderSize + i]; };
  EXPECT_EQ(payload[0], 9) << "version";
  EXPECT_EQ(payload[1], static_cast<std::uint8_t>(MessageType::odometry));
  for (std::size_t i = 0; i < 12; ++i) EXPECT_EQ(at(i), i + 1) << i;
  EXPECT_EQ(at(12), 1) << "status tracking";
  EXPECT_EQ(at(13), 2) << "reset_counter";
  EXPECT_EQ(at(14), 100) << "quality";
  EXPECT_EQ(at(15), 0xFE) << "x_mm -2";
  EXPECT_EQ(at(18), 0xFF);
  EXPECT_EQ(at(27), 0x00) << "qw_e9 1e9 = 0x3B9ACA00";
  EXPECT_EQ(at(28), 0xCA);
  EXPECT_EQ(at(29), 0x9A);
  EXPECT_EQ(at(30), 0x3B);
  for (std::size_t i = 0; i < 4; ++i) EXPECT_EQ(at(85 + i), 0x41 + i) << "keyframes";
  // A status past `lost` is no odometry.
  Bytes body(payload.begin() + kHeaderSize, payload.end() - kCrcSize);
  body[12] = 3;
  EXPECT_FALSE(decode_body(MessageType::odometry, body));
  body[12] = 2;
  EXPECT_TRUE(decode_body(MessageType::odometry, body));
}

TEST(Stages, OneTableGivesTheMasksTheNamesAndTheOrder) {
  EXPECT_EQ(kAlwaysOnStages, stage_bit(Stage::capture) | stage_bit(Stage::publish));
  EXPECT_EQ(kSwitchableStages, 0xFE);
  EXPECT_EQ(kAllStages, 0x1FF) << "total is a time slot, not a stage a mask can hold";
  std::vector<std::string> names;
  for (const StageInfo& s : kStages) {
    EXPECT_EQ(std::string(s.time_field), std::string(s.name) + "_us");
    EXPECT_EQ((s.needs & ~kAllStages), 0) << s.name;
    // A stage needs only stages that run before it.
    EXPECT_LT(s.needs, stage_bit(s.id)) << s.name;
    names.emplace_back(s.name);
  }
  std::sort(names.begin(), names.end());
  EXPECT_EQ(std::adjacent_find(names.begin(), names.end()), names.end()) << "names are unique";
  EXPECT_EQ(stage_info(Stage::sparse).needs, stage_bit(Stage::corners));
  EXPECT_TRUE(has_stage(kAllStages, Stage::detect));
  EXPECT_FALSE(has_stage(kAllStages, Stage::total));
}

TEST(Protocol, BodiesWithWrongLengthsOrCountsAreRejected) {
  EXPECT_FALSE(decode_body(MessageType::set_stages, Bytes{1}));        // short
  EXPECT_FALSE(decode_body(MessageType::set_stages, Bytes{1, 0, 0}));  // long
  Bytes too_many(4, 0);
  too_many.push_back(kMaxDetections + 1);
  EXPECT_FALSE(decode_body(MessageType::detections, too_many));
  EXPECT_FALSE(decode_body(MessageType::command_ack, Bytes{1, 0, 9, 0}));  // unknown status
  EXPECT_FALSE(decode_body(MessageType::command_ack, Bytes{1, 0, 1, 8}));  // unknown reason
  EXPECT_FALSE(decode_body(MessageType::command_ack, Bytes{1, 0, 2}));     // version 2's ack
  EXPECT_TRUE(decode_body(MessageType::command_ack, Bytes{1, 0, 3, 0}));
  EXPECT_TRUE(decode_body(MessageType::command_ack, Bytes{1, 0, 1, 6}));
  EXPECT_TRUE(decode_body(MessageType::command_ack, Bytes{1, 0, 1, 7}));  // no_pairs
  // A depth grid's cells fill whole rows: frame, two fields of view, columns, count, cells.
  const auto grid = [](std::uint8_t columns, std::uint8_t count) {
    Bytes body{1, 0, 0, 0, 0x20, 0x1e, 0x10, 0x14, columns, count};
    for (int i = 0; i < count; ++i) body.insert(body.end(), {0xE8, 0x03});
    return body;
  };
  EXPECT_TRUE(decode_body(MessageType::depth_grid, grid(3, 6)));
  EXPECT_FALSE(decode_body(MessageType::depth_grid, grid(4, 6)));     // a row and a half
  EXPECT_FALSE(decode_body(MessageType::depth_grid, grid(0, 0)));     // no columns
  EXPECT_FALSE(decode_body(MessageType::depth_grid, grid(15, 255)));  // over 240 cells
}

TEST(Protocol, EncodingRejectsImpossibleMessages) {
  Detections detections;
  detections.count = kMaxDetections + 1;
  Bytes out(kMaxFrameSize);
  EXPECT_THROW(encode_frame(detections, 0, out), Error);
  Bytes small(8);
  EXPECT_THROW(encode_frame(Health{}, 0, small), Error);
  DepthGrid grid;
  grid.columns = 4;
  grid.count = 6;  // a row and a half: the peer would refuse it
  EXPECT_THROW(encode_frame(grid, 0, out), Error);
  grid.columns = 0;
  grid.count = 0;
  EXPECT_THROW(encode_frame(grid, 0, out), Error);
  grid.columns = 3;
  EXPECT_NO_THROW(encode_frame(grid, 0, out)) << "an empty grid of 3 columns";
}

}  // namespace
}  // namespace epipole::protocol
