#pragma once

// What the outputs that speak ROS 2 share: the names (the topics' namespace, the frames'
// prefix, both board keys of each such output) and the rig as ROS messages describe it.

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "epipole/calib/calibration.hpp"
#include "ros/ros_messages.hpp"

namespace YAML {
class Node;
}
namespace epipole::yaml {
class Fields;
}

namespace epipole::firmware::ros {

struct RosNames {
  std::string ros_namespace = "/epipole";
  std::string frame_prefix = "epipole_";
  // A topic's ROS name: `name` under the namespace, or itself when absolute ("/tf_static").
  std::string topic(std::string_view name) const;
};

// Reads `namespace` and `frame_prefix` of an output's subsection at `path` when present.
void read_ros_names(const YAML::Node& section, const yaml::Fields& fields, const std::string& path,
                    RosNames& out);

// The rig's frames, its rectified cameras, its baseline and the depth of each disparity (x16):
// the cameras, baseline and depths only with a calibration.
struct RigModel {
  RigModel(const RosNames& names, const std::optional<calib::StereoCalibration>& calibration,
           int max_disparity);
  std::string left_body, left_optical, right_optical;
  std::string ground;  // the ground stage's plane under the rig (ros::ground_transform)
  bool calibrated = false;
  RectifiedCamera left, right;
  double baseline_m = 0;                // metres, from the right camera's P
  std::vector<std::uint16_t> depth_mm;  // by disparity x16 (depth_mm_by_disparity16)
  FrameNames frames() const { return {left_body, left_optical, right_optical}; }
  float focal_px() const { return static_cast<float>(left.p[0]); }
};

}  // namespace epipole::firmware::ros
