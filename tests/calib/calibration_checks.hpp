#pragma once

// Files in other tools' formats and comparing two calibrations' geometry, for the import and
// export tests.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "epipole/calib/calibration.hpp"

namespace epipole::test {

inline std::filesystem::path write_temp(const std::string& name, const std::string& text) {
  const std::filesystem::path file = std::filesystem::path(::testing::TempDir()) / name;
  std::ofstream(file) << text;
  return file;
}

// A matrix's entries, row-major, each with every bit ("%.16e").
template <typename Derived>
std::string numbers(const Eigen::MatrixBase<Derived>& m, const char* separator) {
  std::string out;
  for (Eigen::Index r = 0; r < m.rows(); ++r) {
    for (Eigen::Index c = 0; c < m.cols(); ++c) {
      char text[64];
      std::snprintf(text, sizeof text, "%.16e", static_cast<double>(m(r, c)));
      if (!out.empty()) out += separator;
      out += text;
    }
  }
  return out;
}

inline Eigen::Matrix<double, 1, 5> coefficients(const calib::CameraCalibration& c) {
  const calib::Distortion& d = c.camera.distortion;
  Eigen::Matrix<double, 1, 5> v;
  v << d.k1, d.k2, d.p1, d.p2, d.k3;
  return v;
}

// Every matrix within `tol` (Q, whose entries are larger, within 1000 tol).
inline void expect_geometry(const calib::StereoCalibration& got,
                            const calib::StereoCalibration& want, double tol) {
  const auto distance = [](const auto& a, const auto& b) { return (a - b).cwiseAbs().maxCoeff(); };
  EXPECT_EQ(got.width, want.width);
  EXPECT_EQ(got.height, want.height);
  EXPECT_LE(distance(got.left.camera_matrix(), want.left.camera_matrix()), tol);
  EXPECT_LE(distance(got.right.camera_matrix(), want.right.camera_matrix()), tol);
  EXPECT_LE(distance(coefficients(got.left), coefficients(want.left)), tol);
  EXPECT_LE(distance(coefficients(got.right), coefficients(want.right)), tol);
  EXPECT_LE(distance(got.R, want.R), tol);
  EXPECT_LE(distance(got.T, want.T), tol);
  EXPECT_LE(distance(got.left.rectification, want.left.rectification), tol);
  EXPECT_LE(distance(got.right.rectification, want.right.rectification), tol);
  EXPECT_LE(distance(got.left.projection, want.left.projection), tol);
  EXPECT_LE(distance(got.right.projection, want.right.projection), tol);
  EXPECT_LE(distance(got.Q, want.Q), tol * 1000);
}

}  // namespace epipole::test
