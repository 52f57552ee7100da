#include "ros/rig_model.hpp"

#include <yaml-cpp/yaml.h>

#include "epipole/calib/triangulation.hpp"
#include "epipole/core/yaml_fields.hpp"

namespace epipole::firmware::ros {

std::string RosNames::topic(std::string_view name) const {
  return name.starts_with('/') ? std::string(name) : ros_namespace + "/" + std::string(name);
}

void read_ros_names(const YAML::Node& n, const yaml::Fields& f, const std::string& path,
                    RosNames& out) {
  f.if_present(n, path, "namespace", [&](const YAML::Node& v, const std::string& k) {
    out.ros_namespace = f.text(v, k);
    if (!out.ros_namespace.starts_with('/') || out.ros_namespace.ends_with('/')) {
      f.fail(k, "must start with / and not end with one (/epipole)");
    }
  });
  f.if_present(n, path, "frame_prefix",
               [&](const YAML::Node& v, const std::string& k) { out.frame_prefix = f.text(v, k); });
}

RigModel::RigModel(const RosNames& names,
                   const std::optional<calib::StereoCalibration>& calibration, int max_disparity)
    : left_body(names.frame_prefix + "left"),
      left_optical(names.frame_prefix + "left_optical_frame"),
      right_optical(names.frame_prefix + "right_optical_frame"),
      ground(names.frame_prefix + "ground") {
  if (!calibration) return;
  calibrated = true;
  left = rectified_left(*calibration);
  right = rectified_right(*calibration);
  const double fx = right.p[0];
  baseline_m = fx != 0 ? -right.p[3] / fx : 0.0;
  depth_mm = depth_mm_by_disparity16(calib::Triangulator(*calibration), max_disparity);
}

}  // namespace epipole::firmware::ros
