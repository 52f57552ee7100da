#pragma once

// A rendered path's odometry as `epipole sim` decoded it, against the path's exact poses
// (hal::world_trajectory): the estimate as a TUM file, a picture of both seen from above, and the
// figures at the last pair.
#include <filesystem>
#include <nlohmann/json.hpp>
#include <span>
#include <vector>

#include "epipole/calib/p3p.hpp"

namespace epipole::tools {

// `odometry`: the native odometry messages in the order received (their JSON); `truth`: pose i
// at pair i, at `rate_hz` (a frame number past the path's end is its pose modulo the path, as
// the simulated cameras replay it), taken to the first tracked pair's frame (the odometry's).
// Writes odometry.tum (the tracked poses, at the truth's times) and trajectory.png into
// `directory`. Returns {pairs, tracked, lost, resets, last_frame,
// path_m, end_error_m, end_error_percent, end_heading_deg}; null without a tracked pair.
nlohmann::json check_trajectory(const std::vector<nlohmann::json>& odometry,
                                std::span<const calib::RigidMotion> truth, double rate_hz,
                                const std::filesystem::path& directory);

}  // namespace epipole::tools
