#pragma once

// Eigen matrices out of the calibration files (epipole/core/yaml_fields.hpp reads them).
#include <Eigen/Core>

#include "epipole/core/yaml_fields.hpp"

namespace epipole::calib::detail {

inline Eigen::MatrixXd matrix(const yaml::Fields& fields, const YAML::Node& node,
                              const std::string& key, int rows, int cols) {
  const std::vector<double> values = fields.matrix(node, key, rows, cols);
  return Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
      values.data(), rows, cols);
}

}  // namespace epipole::calib::detail
