#pragma once

#include <array>
#include <optional>

#include "epipole/calib/health.hpp"
#include "epipole/firmware/board_config.hpp"
#include "epipole/firmware/pipeline.hpp"
#include "epipole/firmware/protocol/mavlink.hpp"
#include "epipole/firmware/protocol/messages.hpp"
#include "epipole/firmware/rig_correction.hpp"

namespace epipole::firmware {

// The messages one processed pair becomes, in the protocol's units (docs/protocol.md): what the
// frame loop publishes for it, in this order. Counts that do not fit a field saturate.
struct PairMessages {
  protocol::FrameSummary summary;
  std::optional<protocol::Detections> detections;  // when the detector ran (maybe none found)
  std::optional<protocol::Obstacles> obstacles;    // with the disparity and a calibration
  std::optional<protocol::DepthGrid> depth_grid;   // the same, with the board's depth_grid
  std::optional<protocol::Points> points;          // when the pair has 3-D points to send
  // The stages' own messages (FrameResult::stage_messages), in the order the stages run.
  std::array<const protocol::Message*, protocol::kStageCount> stage_messages{};
};

// Pure functions of their arguments: no state, no allocation.
// `latency`: trigger to publish; `trigger_from_capture`: r.trigger_ns is the left frame's time.
PairMessages pair_messages(const FrameResult& r, hal::Nanoseconds latency,
                           bool trigger_from_capture);
// The calibration message of the last pair's figure, the drift estimate (when there is one) and
// the corrections made (with a calibration).
protocol::CalibrationHealth calibration_health_message(
    const calib::HealthFigure& figure, const std::optional<calib::DriftEstimate>& drift,
    const RigCorrection* correction = nullptr);
// OBSTACLE_DISTANCE for a MAVLink board: the sectors, stamped with the trigger's time, within
// the board's depth range.
mavlink::ObstacleDistance obstacle_distance_message(const protocol::Obstacles& obstacles,
                                                    hal::Nanoseconds trigger_ns,
                                                    const BoardConfig::Obstacles& range);

}  // namespace epipole::firmware
