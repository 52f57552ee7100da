#pragma once

#include <array>
#include <cstdint>
#include <variant>

#include "epipole/firmware/protocol/stages.hpp"

namespace epipole::protocol {

// The Epipole serial protocol (docs/protocol.md says what each version changed). Every number is
// little-endian on the wire; sizes here are the wire sizes. A message is its struct: its type
// byte and name (kType, kName, a value of MessageType), its fields in wire order (the static
// fields(io, m): protocol/fields.hpp says what `io` offers) and its place in the Message variant
// below; the codec, the decoder's checks and the host tool's JSON take all from there.

inline constexpr std::uint8_t kVersion = 9;

enum class MessageType : std::uint8_t {
  // firmware -> robot
  health = 0x01,
  frame_summary = 0x02,
  detections = 0x03,
  obstacles = 0x04,
  points = 0x05,
  calibration_health = 0x06,
  command_ack = 0x07,
  depth_grid = 0x08,
  ground = 0x09,
  odometry = 0x0A,
  // robot -> firmware
  set_trigger_rate = 0x80,
  set_exposure = 0x81,
  set_stages = 0x82,
  snapshot = 0x83,
  record = 0x84,
  recalibrate = 0x85,
  save_calibration = 0x86,
};

// Health flags.
// No calibration file yet: images are taken as rectified and nothing gets a depth.
inline constexpr std::uint16_t kHealthNotCalibrated = 1u << 0;
// Detection is on but its compiled cascade does not exist yet: nothing is detected.
inline constexpr std::uint16_t kHealthNoCascade = 1u << 1;
// The trigger has fired no edge for three periods: externally triggered cameras wait for it (and
// are not reopened for it); nothing is published until it fires again.
inline constexpr std::uint16_t kHealthWaitingForTrigger = 1u << 2;
// The rectification carries a correction made while running (calibration's corrections).
inline constexpr std::uint16_t kHealthRigCorrected = 1u << 3;

// Once a second: rates, latencies, faults.
// Counts are totals since start, modulo 2^32 (they wrap, never stop): a reader takes
// differences modulo 2^32. frames + dropped = the triggers fired up to and with the newest
// frame summary sent before this message.
struct Health {
  static constexpr MessageType kType = MessageType::health;
  static constexpr const char* kName = "health";
  std::uint32_t uptime_ms = 0;
  std::uint32_t frames = 0;          // pairs published
  std::uint32_t dropped = 0;         // triggers not published: the sum of the four dropped_*
  std::uint16_t fps_centi = 0;       // frames per second x 100, over the last second
  std::uint32_t latency_p50_us = 0;  // trigger to publish
  std::uint32_t latency_p99_us = 0;
  std::array<std::uint32_t, kStageCount> stage_us{};  // mean per stage over the last second
  std::uint32_t dropped_stale = 0;                    // paired, but a newer pair was there first
  std::uint32_t dropped_one_side = 0;    // one camera's frame came, the other's never did
  std::uint32_t dropped_both_sides = 0;  // neither camera's frame came (overrun, lost)
  std::uint32_t dropped_corrupt = 0;     // a frame damaged, or the two failed the pair's checks
  std::uint32_t camera_timeouts = 0;
  std::uint32_t camera_reopens = 0;
  std::uint32_t trigger_losses = 0;
  std::uint32_t link_reopens = 0;
  std::uint32_t unpaired_frames = 0;
  std::uint32_t bad_commands = 0;
  std::uint32_t messages_dropped = 0;   // not sent: the link's byte budget or queue was full
  std::uint32_t snapshot_failures = 0;  // snapshots that could not be written
  std::uint16_t flags = 0;              // kHealth* bits: the firmware's state
  // The frame loop's occupancy: how long pairs waited for it (from the later of a pair's two
  // frames to the start of its processing), and the share of the second it spent on pairs.
  std::uint32_t wait_p50_us = 0;
  std::uint32_t wait_p99_us = 0;
  std::uint16_t busy_permille = 0;
  // Trigger glitches (version 5): edges ignored as bounces (closer than a quarter period after
  // the one before), and pairs dropped because no edge lay at their time (a missed edge; each
  // is in dropped_* too, under the trigger it was taken for).
  std::uint32_t trigger_bounces = 0;
  std::uint32_t pairs_off_trigger = 0;
  // The outputs (version 6, docs/outputs.md): pairs they dropped because their work was behind,
  // and their work's failures (a full disk, a network error), summed over the outputs.
  std::uint32_t outputs_dropped = 0;
  std::uint32_t output_failures = 0;
  template <class Io, class Self>
  static void fields(Io& io, Self& m) {
    io("uptime_ms", m.uptime_ms);
    io("frames", m.frames);
    io("dropped", m.dropped);
    io("fps_centi", m.fps_centi);
    io("latency_p50_us", m.latency_p50_us);
    io("latency_p99_us", m.latency_p99_us);
    for (const StageInfo& s : kStages) io(s.time_field, m.stage_us[static_cast<std::size_t>(s.id)]);
    io("dropped_stale", m.dropped_stale);
    io("dropped_one_side", m.dropped_one_side);
    io("dropped_both_sides", m.dropped_both_sides);
    io("dropped_corrupt", m.dropped_corrupt);
    io("camera_timeouts", m.camera_timeouts);
    io("camera_reopens", m.camera_reopens);
    io("trigger_losses", m.trigger_losses);
    io("link_reopens", m.link_reopens);
    io("unpaired_frames", m.unpaired_frames);
    io("bad_commands", m.bad_commands);
    io("messages_dropped", m.messages_dropped);
    io("snapshot_failures", m.snapshot_failures);
    io("flags", m.flags);
    io("wait_p50_us", m.wait_p50_us);
    io("wait_p99_us", m.wait_p99_us);
    io("busy_permille", m.busy_permille);
    io("trigger_bounces", m.trigger_bounces);
    io("pairs_off_trigger", m.pairs_off_trigger);
    io("outputs_dropped", m.outputs_dropped);
    io("output_failures", m.output_failures);
  }
  friend bool operator==(const Health&, const Health&) = default;
};

// Frame flags.
// trigger_ns is the left frame's capture time: no trigger edge was recorded for the pair.
inline constexpr std::uint8_t kFrameTriggerFromCapture = 1u << 0;

// One per processed pair.
struct FrameSummary {
  static constexpr MessageType kType = MessageType::frame_summary;
  static constexpr const char* kName = "frame";
  std::uint32_t frame = 0;       // trigger sequence number
  std::uint64_t trigger_ns = 0;  // trigger edge, CLOCK_MONOTONIC
  std::uint32_t latency_us = 0;  // trigger to this message
  std::uint16_t corners_left = 0;
  std::uint16_t corners_right = 0;
  std::uint16_t valid_disparity_permille = 0;
  std::uint8_t detections = 0;
  std::uint16_t points = 0;
  std::uint8_t flags = 0;  // kFrame* bits
  template <class Io, class Self>
  static void fields(Io& io, Self& m) {
    io("frame", m.frame);
    io("trigger_ns", m.trigger_ns);
    io("latency_us", m.latency_us);
    io("corners_left", m.corners_left);
    io("corners_right", m.corners_right);
    io("valid_disparity_permille", m.valid_disparity_permille);
    io("detections", m.detections);
    io("points", m.points);
    io("flags", m.flags);
  }
  friend bool operator==(const FrameSummary&, const FrameSummary&) = default;
};

inline constexpr std::uint16_t kUnknownDepth = 0xFFFF;

struct Detection {
  std::uint16_t x = 0, y = 0, width = 0, height = 0;  // rectified left image, pixels
  std::uint8_t neighbors = 0;                         // raw hits grouped into this box
  std::uint16_t depth_mm = kUnknownDepth;
  friend bool operator==(const Detection&, const Detection&) = default;
};

inline constexpr int kMaxDetections = 32;
struct Detections {
  static constexpr MessageType kType = MessageType::detections;
  static constexpr const char* kName = "detections";
  std::uint32_t frame = 0;
  std::uint8_t count = 0;
  std::array<Detection, kMaxDetections> items{};
  template <class Io, class Self>
  static void fields(Io& io, Self& m) {
    io("frame", m.frame);
    io.list("boxes", m.count, kMaxDetections, m.items, [](Io& item_io, auto& d) {
      item_io("x", d.x);
      item_io("y", d.y);
      item_io("width", d.width);
      item_io("height", d.height);
      item_io("neighbors", d.neighbors);
      item_io("depth_mm", d.depth_mm);
    });
  }
  friend bool operator==(const Detections&, const Detections&) = default;
};

inline constexpr int kMaxSectors = 72;
struct Obstacles {
  static constexpr MessageType kType = MessageType::obstacles;
  static constexpr const char* kName = "obstacles";
  std::uint32_t frame = 0;
  std::uint16_t field_of_view_centideg = 0;  // horizontal, split evenly into `count` sectors
  std::uint8_t count = 0;
  std::array<std::uint16_t, kMaxSectors> nearest_mm{};  // kUnknownDepth: nothing seen
  template <class Io, class Self>
  static void fields(Io& io, Self& m) {
    io("frame", m.frame);
    io("field_of_view_centideg", m.field_of_view_centideg);
    io.list("nearest_mm", m.count, kMaxSectors, m.nearest_mm,
            [](Io& item_io, auto& nearest) { item_io("mm", nearest); });
  }
  friend bool operator==(const Obstacles&, const Obstacles&) = default;
};

// The nearest depth in each cell of a grid over the whole rectified left view (the board's
// depth_grid): cells left to right, then top to bottom, splitting the horizontal and the vertical
// field of view evenly by angle. count is columns x rows.
inline constexpr int kMaxGridCells = 240;
struct DepthGrid {
  static constexpr MessageType kType = MessageType::depth_grid;
  static constexpr const char* kName = "depth_grid";
  std::uint32_t frame = 0;
  std::uint16_t field_of_view_centideg = 0;  // horizontal
  std::uint16_t vertical_field_of_view_centideg = 0;
  std::uint8_t columns = 0;
  std::uint8_t count = 0;
  std::array<std::uint16_t, kMaxGridCells> nearest_mm{};  // kUnknownDepth: nothing seen
  template <class Io, class Self>
  static void fields(Io& io, Self& m) {
    io("frame", m.frame);
    io("field_of_view_centideg", m.field_of_view_centideg);
    io("vertical_field_of_view_centideg", m.vertical_field_of_view_centideg);
    io("columns", m.columns);
    io.list("nearest_mm", m.count, kMaxGridCells, m.nearest_mm,
            [](Io& item_io, auto& nearest) { item_io("mm", nearest); });
  }
  friend bool operator==(const DepthGrid&, const DepthGrid&) = default;
};

// The ground under the rig (the ground stage, docs/vision.md), in the rectified left camera's
// frame: its height above the ground, and its pitch and roll against it. Version 7.
inline constexpr std::uint8_t kGroundFound = 1u << 0;  // flags: else the other fields are 0
struct Ground {
  static constexpr MessageType kType = MessageType::ground;
  static constexpr const char* kName = "ground";
  std::uint32_t frame = 0;
  std::uint8_t flags = 0;
  std::uint16_t height_mm = 0;         // the camera's centre above the ground
  std::int16_t pitch_cdeg = 0;         // the optical axis below the horizontal: looking down > 0
  std::int16_t roll_cdeg = 0;          // the image's right side lower > 0
  std::uint16_t inliers_permille = 0;  // of the pixels with a disparity, those on the ground
  template <class Io, class Self>
  static void fields(Io& io, Self& m) {
    io("frame", m.frame);
    io("flags", m.flags);
    io("height_mm", m.height_mm);
    io("pitch_cdeg", m.pitch_cdeg);
    io("roll_cdeg", m.roll_cdeg);
    io("inliers_permille", m.inliers_permille);
  }
  friend bool operator==(const Ground&, const Ground&) = default;
};

// Where the rig is and how it moves (the odometry stage, docs/odometry.md), version 9. The
// odometry frame is the left camera's at the first keyframe, OpenCV's axes (x right, y down,
// z forward); the pose is the left camera's in it. `status` lost: the pose is the last one
// tracked, kept; starting: no pose yet (every other field 0). `reset_counter` goes up each time
// the pose starts again after lost tracking (from the pose it had: the frame stays).
enum class OdometryStatus : std::uint8_t { starting = 0, tracking = 1, lost = 2 };
constexpr OdometryStatus last_value(OdometryStatus) {
  return OdometryStatus::lost;
}
struct Odometry {
  static constexpr MessageType kType = MessageType::odometry;
  static constexpr const char* kName = "odometry";
  std::uint32_t frame = 0;
  std::uint64_t trigger_ns = 0;  // the pair's time, as its frame summary's
  OdometryStatus status = OdometryStatus::starting;
  std::uint8_t reset_counter = 0;
  std::uint8_t quality = 0;                   // 0..100: the share of features consistent, scaled
  std::int32_t x_mm = 0, y_mm = 0, z_mm = 0;  // the camera's position
  // Its orientation (camera to odometry frame), a unit quaternion x 1e9, w >= 0.
  std::int32_t qw_e9 = 1'000'000'000, qx_e9 = 0, qy_e9 = 0, qz_e9 = 0;
  std::int32_t vx_mm_s = 0, vy_mm_s = 0, vz_mm_s = 0;        // velocity, odometry frame
  std::int32_t wx_mrad_s = 0, wy_mrad_s = 0, wz_mrad_s = 0;  // angular velocity, camera frame
  // The pose's uncertainty: standard deviations of the position (odometry frame's axes) and of
  // the rotation about them (the covariance's diagonal; saturated at 65 535).
  std::uint16_t sx_mm = 0, sy_mm = 0, sz_mm = 0;
  std::uint16_t srx_cdeg = 0, sry_cdeg = 0, srz_cdeg = 0;
  std::uint16_t features = 0;  // the keyframe's features looked for
  std::uint16_t tracked = 0;   // found again in this pair
  std::uint16_t inliers = 0;   // consistent with its motion
  std::uint32_t keyframes = 0;
  template <class Io, class Self>
  static void fields(Io& io, Self& m) {
    io("frame", m.frame);
    io("trigger_ns", m.trigger_ns);
    io("status", m.status);
    io("reset_counter", m.reset_counter);
    io("quality", m.quality);
    io("x_mm", m.x_mm);
    io("y_mm", m.y_mm);
    io("z_mm", m.z_mm);
    io("qw_e9", m.qw_e9);
    io("qx_e9", m.qx_e9);
    io("qy_e9", m.qy_e9);
    io("qz_e9", m.qz_e9);
    io("vx_mm_s", m.vx_mm_s);
    io("vy_mm_s", m.vy_mm_s);
    io("vz_mm_s", m.vz_mm_s);
    io("wx_mrad_s", m.wx_mrad_s);
    io("wy_mrad_s", m.wy_mrad_s);
    io("wz_mrad_s", m.wz_mrad_s);
    io("sx_mm", m.sx_mm);
    io("sy_mm", m.sy_mm);
    io("sz_mm", m.sz_mm);
    io("srx_cdeg", m.srx_cdeg);
    io("sry_cdeg", m.sry_cdeg);
    io("srz_cdeg", m.srz_cdeg);
    io("features", m.features);
    io("tracked", m.tracked);
    io("inliers", m.inliers);
    io("keyframes", m.keyframes);
  }
  friend bool operator==(const Odometry&, const Odometry&) = default;
};

struct Point {
  std::uint16_t u_x16 = 0, v_x16 = 0;         // rectified left image position x 16
  std::int32_t x_mm = 0, y_mm = 0, z_mm = 0;  // left camera frame
  friend bool operator==(const Point&, const Point&) = default;
};

inline constexpr int kMaxPoints = 48;
struct Points {
  static constexpr MessageType kType = MessageType::points;
  static constexpr const char* kName = "points";
  std::uint32_t frame = 0;
  std::uint8_t count = 0;
  std::array<Point, kMaxPoints> items{};
  template <class Io, class Self>
  static void fields(Io& io, Self& m) {
    io("frame", m.frame);
    io.list("points", m.count, kMaxPoints, m.items, [](Io& item_io, auto& p) {
      item_io("u_x16", p.u_x16);
      item_io("v_x16", p.v_x16);
      item_io("x_mm", p.x_mm);
      item_io("y_mm", p.y_mm);
      item_io("z_mm", p.z_mm);
    });
  }
  friend bool operator==(const Points&, const Points&) = default;
};

// calibration.flags
inline constexpr std::uint8_t kDriftEstimated = 1u << 0;  // pitch_mdeg .. roll_sigma_mdeg hold one
inline constexpr std::uint8_t kRigCorrecting = 1u << 1;   // a corrected map is being rebuilt

struct CalibrationHealth {
  static constexpr MessageType kType = MessageType::calibration_health;
  static constexpr const char* kName = "calibration";
  std::uint16_t matches = 0;               // the last pair's matches measured
  std::int16_t median_offset_centipx = 0;  // their vertical offset (right - left), x 100: median
  std::uint16_t p90_offset_centipx = 0;    // and the 90th percentile of its size
  std::uint8_t flags = 0;
  std::uint16_t window_pairs = 0;  // pairs of the estimate's window with matches
  std::int16_t pitch_mdeg = 0;     // the right camera's turn since the calibration, 1/1000 degree
  std::int16_t roll_mdeg = 0;
  std::uint16_t pitch_sigma_mdeg = 0;  // one standard deviation
  std::uint16_t roll_sigma_mdeg = 0;
  std::uint16_t corrections = 0;          // made while running (calibration_health)
  std::int16_t corrected_pitch_mdeg = 0;  // the rectification's correction from the file
  std::int16_t corrected_roll_mdeg = 0;
  template <class Io, class Self>
  static void fields(Io& io, Self& m) {
    io("matches", m.matches);
    io("median_offset_centipx", m.median_offset_centipx);
    io("p90_offset_centipx", m.p90_offset_centipx);
    io("flags", m.flags);
    io("window_pairs", m.window_pairs);
    io("pitch_mdeg", m.pitch_mdeg);
    io("roll_mdeg", m.roll_mdeg);
    io("pitch_sigma_mdeg", m.pitch_sigma_mdeg);
    io("roll_sigma_mdeg", m.roll_sigma_mdeg);
    io("corrections", m.corrections);
    io("corrected_pitch_mdeg", m.corrected_pitch_mdeg);
    io("corrected_roll_mdeg", m.corrected_roll_mdeg);
  }
  friend bool operator==(const CalibrationHealth&, const CalibrationHealth&) = default;
};

// ok: applied. rejected: not applied, for `reason`. unsupported: this board cannot do it (no
// trigger line to set the rate of). duplicate: the sequence number of a command already
// received (the robot sent it again): not applied again.
// A one-byte enum of a message says its largest value (the decoder rejects any above it) by an
// overload of last_value().
enum class AckStatus : std::uint8_t { ok = 0, rejected = 1, unsupported = 2, duplicate = 3 };
constexpr AckStatus last_value(AckStatus) {
  return AckStatus::duplicate;
}
// Why a command was rejected (none otherwise).
enum class AckReason : std::uint8_t {
  none = 0,
  out_of_range = 1,   // a value the protocol, the hardware or the board file does not allow
  timing = 2,         // the board's timing could not follow it (camera timeout, watchdog, pairing)
  busy = 3,           // one is already pending (snapshot), or too many commands came at once
  storage = 4,        // the snapshot limit or the free-space reserve is reached
  failed = 5,         // tried and failed (a snapshot that could not be written)
  not_a_command = 6,  // a message the firmware sends, not one it takes
  no_pairs = 7,       // no pair to take it from: a camera is gone or the trigger stopped
};
constexpr AckReason last_value(AckReason) {
  return AckReason::no_pairs;
}
struct CommandAck {
  static constexpr MessageType kType = MessageType::command_ack;
  static constexpr const char* kName = "ack";
  std::uint16_t command_sequence = 0;
  AckStatus status = AckStatus::ok;
  AckReason reason = AckReason::none;
  template <class Io, class Self>
  static void fields(Io& io, Self& m) {
    io("command_sequence", m.command_sequence);
    io("status", m.status);
    io("reason", m.reason);
  }
  friend bool operator==(const CommandAck&, const CommandAck&) = default;
};

struct SetTriggerRate {
  static constexpr MessageType kType = MessageType::set_trigger_rate;
  static constexpr const char* kName = "set_trigger_rate";
  std::uint32_t rate_millihz = 0;
  template <class Io, class Self>
  static void fields(Io& io, Self& m) {
    io("rate_millihz", m.rate_millihz);
  }
  friend bool operator==(const SetTriggerRate&, const SetTriggerRate&) = default;
};
struct SetExposure {
  static constexpr MessageType kType = MessageType::set_exposure;
  static constexpr const char* kName = "set_exposure";
  std::uint32_t exposure_us = 0;
  std::uint16_t gain_centidb = 0;
  template <class Io, class Self>
  static void fields(Io& io, Self& m) {
    io("exposure_us", m.exposure_us);
    io("gain_centidb", m.gain_centidb);
  }
  friend bool operator==(const SetExposure&, const SetExposure&) = default;
};
struct SetStages {
  static constexpr MessageType kType = MessageType::set_stages;
  static constexpr const char* kName = "set_stages";
  StageMask enabled_mask = 0;  // bit per Stage (capture and publish always run)
  template <class Io, class Self>
  static void fields(Io& io, Self& m) {
    io("enabled_mask", m.enabled_mask);
  }
  friend bool operator==(const SetStages&, const SetStages&) = default;
};
struct Snapshot {
  static constexpr MessageType kType = MessageType::snapshot;
  static constexpr const char* kName = "snapshot";
  template <class Io, class Self>
  static void fields(Io&, Self&) {}
  friend bool operator==(const Snapshot&, const Snapshot&) = default;
};

// Starts or stops the board's recording (the mcap output, docs/outputs.md), version 6.
enum class RecordAction : std::uint8_t { stop = 0, start = 1 };
constexpr RecordAction last_value(RecordAction) {
  return RecordAction::start;
}
struct Record {
  static constexpr MessageType kType = MessageType::record;
  static constexpr const char* kName = "record";
  RecordAction action = RecordAction::start;
  std::uint16_t duration_s = 0;  // start: stop after this long on the board's clock; 0: until stop
  template <class Io, class Self>
  static void fields(Io& io, Self& m) {
    io("action", m.action);
    io("duration_s", m.duration_s);
  }
  friend bool operator==(const Record&, const Record&) = default;
};

// Corrects the rig now from the drift's window (docs/calibration.md), whatever the board's
// online_correction says; answered once the corrected map is in place. Version 8.
struct Recalibrate {
  static constexpr MessageType kType = MessageType::recalibrate;
  static constexpr const char* kName = "recalibrate";
  template <class Io, class Self>
  static void fields(Io&, Self&) {}
  friend bool operator==(const Recalibrate&, const Recalibrate&) = default;
};

// Writes the calibration in use (with its corrections) beside the board's calibration file,
// which is kept; answered once written. Version 8.
struct SaveCalibration {
  static constexpr MessageType kType = MessageType::save_calibration;
  static constexpr const char* kName = "save_calibration";
  template <class Io, class Self>
  static void fields(Io&, Self&) {}
  friend bool operator==(const SaveCalibration&, const SaveCalibration&) = default;
};

using Message = std::variant<Health, FrameSummary, Detections, Obstacles, Points, CalibrationHealth,
                             CommandAck, SetTriggerRate, SetExposure, SetStages, Snapshot,
                             DepthGrid, Record, Ground, Recalibrate, SaveCalibration, Odometry>;

MessageType type_of(const Message& message);
const char* name_of(MessageType type);

}  // namespace epipole::protocol
