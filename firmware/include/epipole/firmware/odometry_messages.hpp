#pragma once

// The odometry (firmware/visual_odometry.hpp) as the robot receives it: the native `odometry`
// message (docs/protocol.md) and MAVLink's ODOMETRY for PX4 and ArduPilot. Pure functions: no
// state, no allocation.
#include <cstdint>

#include "epipole/firmware/protocol/mavlink.hpp"
#include "epipole/firmware/protocol/messages.hpp"
#include "epipole/firmware/visual_odometry.hpp"

namespace epipole::firmware {

// In the protocol's units, in the odometry frame (the first keyframe's left camera, OpenCV's
// axes). A field that does not fit saturates.
protocol::Odometry odometry_message(const OdometryState& state, std::uint32_t frame,
                                    hal::Nanoseconds trigger_ns);

// MAVLink's ODOMETRY, with the camera as the vehicle's body, looking forward: frame_id LOCAL_FRD
// (the first keyframe's body axes: x forward along the optical axis, y right, z down), child
// BODY_FRD; position and attitude in the local frame, velocity and rates in the body's; the
// pose's covariance in the local frame's axes (x, y, z, then rotations about them), the
// velocity's unknown. time_usec is the pair's trigger on the board's clock (which TIMESYNC
// answers with). Lost: the last pose, quality -1. Not to be sent while starting (no pose).
mavlink::Odometry mavlink_odometry(const OdometryState& state, hal::Nanoseconds trigger_ns);

}  // namespace epipole::firmware
