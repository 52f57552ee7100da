#pragma once

// Each message's wire layout, written once: the order of its fields, with their names. The
// encoder, the decoder and the host tool's JSON output are all visitors of these lists.
//
// A visitor `io` provides:
//   io(name, value)                        one number (or enum of one byte)
//   io.list(name, count, limit, items, f)  a u8 count (at most limit), then f(io, items[i])
//                                          for each of the first count items
#include "epipole/firmware/protocol/messages.hpp"

namespace epipole::protocol {

template <class Io, class M>
requires std::is_same_v<std::remove_const_t<M>, Health>
void fields(Io& io, M& m) {
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
}

template <class Io, class M>
requires std::is_same_v<std::remove_const_t<M>, FrameSummary>
void fields(Io& io, M& m) {
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

template <class Io, class M>
requires std::is_same_v<std::remove_const_t<M>, Detections>
void fields(Io& io, M& m) {
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

template <class Io, class M>
requires std::is_same_v<std::remove_const_t<M>, Obstacles>
void fields(Io& io, M& m) {
  io("frame", m.frame);
  io("field_of_view_centideg", m.field_of_view_centideg);
  io.list("nearest_mm", m.count, kMaxSectors, m.nearest_mm,
          [](Io& item_io, auto& nearest) { item_io("mm", nearest); });
}

template <class Io, class M>
requires std::is_same_v<std::remove_const_t<M>, DepthGrid>
void fields(Io& io, M& m) {
  io("frame", m.frame);
  io("field_of_view_centideg", m.field_of_view_centideg);
  io("vertical_field_of_view_centideg", m.vertical_field_of_view_centideg);
  io("columns", m.columns);
  io.list("nearest_mm", m.count, kMaxGridCells, m.nearest_mm,
          [](Io& item_io, auto& nearest) { item_io("mm", nearest); });
}

template <class Io, class M>
requires std::is_same_v<std::remove_const_t<M>, Points>
void fields(Io& io, M& m) {
  io("frame", m.frame);
  io.list("points", m.count, kMaxPoints, m.items, [](Io& item_io, auto& p) {
    item_io("u_x16", p.u_x16);
    item_io("v_x16", p.v_x16);
    item_io("x_mm", p.x_mm);
    item_io("y_mm", p.y_mm);
    item_io("z_mm", p.z_mm);
  });
}

template <class Io, class M>
requires std::is_same_v<std::remove_const_t<M>, CalibrationHealth>
void fields(Io& io, M& m) {
  io("matches", m.matches);
  io("median_offset_centipx", m.median_offset_centipx);
  io("p90_offset_centipx", m.p90_offset_centipx);
}

template <class Io, class M>
requires std::is_same_v<std::remove_const_t<M>, CommandAck>
void fields(Io& io, M& m) {
  io("command_sequence", m.command_sequence);
  io("status", m.status);
  io("reason", m.reason);
}

template <class Io, class M>
requires std::is_same_v<std::remove_const_t<M>, SetTriggerRate>
void fields(Io& io, M& m) {
  io("rate_millihz", m.rate_millihz);
}

template <class Io, class M>
requires std::is_same_v<std::remove_const_t<M>, SetExposure>
void fields(Io& io, M& m) {
  io("exposure_us", m.exposure_us);
  io("gain_centidb", m.gain_centidb);
}

template <class Io, class M>
requires std::is_same_v<std::remove_const_t<M>, SetStages>
void fields(Io& io, M& m) {
  io("enabled_mask", m.enabled_mask);
}

template <class Io, class M>
requires std::is_same_v<std::remove_const_t<M>, Snapshot>
void fields(Io&, M&) {}

}  // namespace epipole::protocol
