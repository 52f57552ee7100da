#pragma once

// A calibration's matrices as OpenCV takes them (CV_64F), for the host side: FileStorage's
// export and the rectification maps `epipole bench` gives OpenCV.
#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <opencv2/core/eigen.hpp>

#include "epipole/calib/camera_model.hpp"

namespace epipole::tools {

inline cv::Mat opencv_matrix(const Eigen::MatrixXd& m) {
  cv::Mat out;
  cv::eigen2cv(m, out);
  return out;
}

// k1 k2 p1 p2 k3, the 1x5 vector OpenCV's functions and files use.
inline cv::Mat opencv_coefficients(const calib::Distortion& d) {
  return (cv::Mat_<double>(1, 5) << d.k1, d.k2, d.p1, d.p2, d.k3);
}

}  // namespace epipole::tools
