// The calibration file: schema version 1 (docs/calibration.md).
#include "epipole/calib/calibration.hpp"

#include <yaml-cpp/yaml.h>

#include <Eigen/Dense>
#include <cmath>
#include <ctime>

#include "epipole/core/error.hpp"
#include "epipole/core/text_file.hpp"
#include "yaml_matrix.hpp"

namespace epipole::calib {

namespace {

constexpr const char* kFormat = "epipole-stereo-calibration";
constexpr const char* kDistortionModel = "radial-tangential";
constexpr int kMaxImageSize = 32767;  // what the fixed-point maps can address
constexpr double kRotationTolerance = 1e-6;
constexpr double kParallelTolerance = 1e-5;

template <typename Derived>
void require_finite(const Eigen::MatrixBase<Derived>& m, const std::string& key) {
  require(m.allFinite(), key, ": has a non-finite number");
}

void require_rotation(const Eigen::Matrix3d& r, const std::string& key) {
  require_finite(r, key);
  const double off = (r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  require(off <= kRotationTolerance && r.determinant() > 0, key,
          ": is not a rotation matrix (R^T R differs from I by ", off, ", det ", r.determinant(),
          ")");
}

void validate_camera(const CameraCalibration& c, const std::string& side, bool is_right) {
  const std::string key = "cameras." + side;
  const Intrinsics& k = c.camera.intrinsics;
  require(std::isfinite(k.fx) && std::isfinite(k.fy) && std::isfinite(k.cx) && std::isfinite(k.cy),
          key, ".K: has a non-finite number");
  require(k.fx > 0 && k.fy > 0, key, ".K: focal lengths must be > 0 (fx ", k.fx, ", fy ", k.fy,
          ")");
  const Distortion& d = c.camera.distortion;
  require(std::isfinite(d.k1) && std::isfinite(d.k2) && std::isfinite(d.p1) &&
              std::isfinite(d.p2) && std::isfinite(d.k3),
          key, ".distortion.coefficients: has a non-finite number");

  const std::string r_key = is_right ? "rectification.R2" : "rectification.R1";
  const std::string p_key = is_right ? "rectification.P2" : "rectification.P1";
  require_rotation(c.rectification, r_key);
  const Eigen::Matrix<double, 3, 4>& p = c.projection;
  require_finite(p, p_key);
  require(p(0, 0) > 0 && p(1, 1) > 0, p_key, ": focal lengths must be > 0");
  const double scale = p(0, 0);
  const bool shape = std::abs(p(0, 1)) <= 1e-9 * scale && std::abs(p(1, 0)) <= 1e-9 * scale &&
                     p(2, 0) == 0 && p(2, 1) == 0 && p(2, 2) == 1 && p(2, 3) == 0;
  require(shape, p_key, ": is not a rectified projection [f 0 cx tx; 0 f cy ty; 0 0 1 0]");
  if (is_right) {
    require(p(0, 3) != 0 || p(1, 3) != 0, p_key,
            ": has no baseline (P2(0,3) and P2(1,3) are both 0)");
  } else {
    require(p(0, 3) == 0 && p(1, 3) == 0, p_key, ": the left projection must have no translation");
  }
}

// The rows of a matrix as YAML flow sequences, one per line.
template <typename Derived>
void emit_matrix(YAML::Emitter& out, const char* key, const Eigen::MatrixBase<Derived>& m) {
  out << YAML::Key << key << YAML::Value << YAML::BeginSeq;
  for (Eigen::Index r = 0; r < m.rows(); ++r) {
    out << YAML::Flow << YAML::BeginSeq;
    for (Eigen::Index c = 0; c < m.cols(); ++c) out << m(r, c);
    out << YAML::EndSeq;
  }
  out << YAML::EndSeq;
}

void emit_camera(YAML::Emitter& out, const char* side, const CameraCalibration& c) {
  out << YAML::Key << side << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "id" << YAML::Value << YAML::DoubleQuoted << c.id;
  emit_matrix(out, "K", c.camera_matrix());
  const Distortion& d = c.camera.distortion;
  out << YAML::Key << "distortion" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "model" << YAML::Value << kDistortionModel;
  out << YAML::Key << "coefficients" << YAML::Value << YAML::Flow << YAML::BeginSeq << d.k1 << d.k2
      << d.p1 << d.p2 << d.k3 << YAML::EndSeq;
  out << YAML::Comment("k1 k2 p1 p2 k3");
  out << YAML::EndMap;
  out << YAML::EndMap;
}

CameraCalibration read_camera(const yaml::Fields& f, const YAML::Node& cameras, const char* side) {
  const std::string path = std::string("cameras.") + side;
  const YAML::Node node = f.child(cameras, "cameras", side);
  f.only_keys(node, path, {"id", "K", "distortion"});
  CameraCalibration c;
  c.id = f.text(f.child(node, path, "id"), path + ".id");
  const Eigen::MatrixXd k = detail::matrix(f, f.child(node, path, "K"), path + ".K", 3, 3);
  const double fx = k(0, 0);
  const bool pinhole = std::abs(k(0, 1)) <= 1e-9 * std::abs(fx) && k(1, 0) == 0 && k(2, 0) == 0 &&
                       k(2, 1) == 0 && k(2, 2) == 1;
  if (!pinhole) {
    f.fail(path + ".K", "must be [fx 0 cx; 0 fy cy; 0 0 1] (skew is not supported)");
  }
  c.camera.intrinsics = {k(0, 0), k(1, 1), k(0, 2), k(1, 2)};

  const std::string dpath = path + ".distortion";
  const YAML::Node distortion = f.child(node, path, "distortion");
  f.only_keys(distortion, dpath, {"model", "coefficients"});
  const std::string model = f.text(f.child(distortion, dpath, "model"), dpath + ".model");
  if (model != kDistortionModel) {
    f.fail(dpath + ".model",
           "'" + model + "' is not supported (only " + kDistortionModel + ": k1 k2 p1 p2 k3)");
  }
  const std::vector<double> coefficients =
      f.numbers(f.child(distortion, dpath, "coefficients"), dpath + ".coefficients");
  if (coefficients.size() != 5) {
    f.fail(dpath + ".coefficients",
           cat("expected 5 numbers (k1 k2 p1 p2 k3), found ", coefficients.size()));
  }
  c.camera.distortion = {coefficients[0], coefficients[1], coefficients[2], coefficients[3],
                         coefficients[4]};
  return c;
}

}  // namespace

Eigen::Matrix3d CameraCalibration::camera_matrix() const {
  const Intrinsics& k = camera.intrinsics;
  Eigen::Matrix3d m;
  m << k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1;
  return m;
}

void validate(const StereoCalibration& c) {
  require(c.width >= 1 && c.height >= 1 && c.width <= kMaxImageSize && c.height <= kMaxImageSize,
          "image_size: ", c.width, "x", c.height, " is outside [1, ", kMaxImageSize, "]");
  validate_camera(c.left, "left", false);
  validate_camera(c.right, "right", true);
  require_rotation(c.R, "extrinsics.R");
  require_finite(c.T, "extrinsics.T");
  require(c.T.norm() > 0, "extrinsics.T: the baseline is zero");
  require_finite(c.Q, "rectification.Q");
  require(c.Q(3, 2) != 0, "rectification.Q: Q(3,2) is 0 (no baseline)");
  // The rectified frames are parallel: R2 (R x + T) and R1 x differ by a translation only.
  const double parallel =
      (c.right.rectification * c.R - c.left.rectification).cwiseAbs().maxCoeff();
  require(parallel <= kParallelTolerance, "rectification.R2: R2 * R differs from R1 by ", parallel,
          ": the rectification does not belong to these extrinsics");
  if (c.rms) {
    require(std::isfinite(*c.rms) && *c.rms >= 0, "quality.rms: ", *c.rms, " is not >= 0");
  }
  for (std::size_t i = 0; i < c.views.size(); ++i) {
    const ViewError& v = c.views[i];
    require(std::isfinite(v.left_rms) && v.left_rms >= 0 && std::isfinite(v.right_rms) &&
                v.right_rms >= 0,
            "quality.views[", i, "]: errors must be finite and >= 0");
  }
}

namespace {

// The header: a calibration file of a version this build reads.
void read_header(const yaml::Fields& f, const YAML::Node& root, const std::string& file_name) {
  if (!root.IsMap()) {
    throw Error(cat(file_name,
                    ": not a calibration file (expected a YAML map with format: ", kFormat, ")"));
  }
  const std::string format = f.text(f.child(root, "", "format"), "format");
  if (format != kFormat) {
    f.fail("format", "'" + format + "' is not " + kFormat + " (not an Epipole calibration file)");
  }
  const int version = f.integer(f.child(root, "", "version"), "version");
  if (version > StereoCalibration::kVersion) {
    f.fail("version", cat(version, " is newer than this build reads (", StereoCalibration::kVersion,
                          "): update epipole"));
  }
  if (version < 1) f.fail("version", cat(version, " is not a valid version"));
  f.only_keys(root, "",
              {"format", "version", "date", "source", "image_size", "cameras", "extrinsics",
               "rectification", "quality"});
}

void read_geometry(const yaml::Fields& f, const YAML::Node& root, StereoCalibration& c) {
  const YAML::Node extrinsics = f.child(root, "", "extrinsics");
  f.only_keys(extrinsics, "extrinsics", {"R", "T"});
  c.R = detail::matrix(f, f.child(extrinsics, "extrinsics", "R"), "extrinsics.R", 3, 3);
  const std::vector<double> t = f.numbers(f.child(extrinsics, "extrinsics", "T"), "extrinsics.T");
  if (t.size() != 3) f.fail("extrinsics.T", cat("expected 3 numbers, found ", t.size()));
  c.T = {t[0], t[1], t[2]};

  const std::string rp = "rectification";
  const YAML::Node rect = f.child(root, "", "rectification");
  f.only_keys(rect, rp, {"R1", "R2", "P1", "P2", "Q"});
  c.left.rectification = detail::matrix(f, f.child(rect, rp, "R1"), rp + ".R1", 3, 3);
  c.right.rectification = detail::matrix(f, f.child(rect, rp, "R2"), rp + ".R2", 3, 3);
  c.left.projection = detail::matrix(f, f.child(rect, rp, "P1"), rp + ".P1", 3, 4);
  c.right.projection = detail::matrix(f, f.child(rect, rp, "P2"), rp + ".P2", 3, 4);
  c.Q = detail::matrix(f, f.child(rect, rp, "Q"), rp + ".Q", 4, 4);
}

void read_quality(const yaml::Fields& f, const YAML::Node& root, StereoCalibration& c) {
  const YAML::Node quality = f.optional_child(root, "", "quality");
  if (!quality) return;
  f.only_keys(quality, "quality", {"rms", "views"});
  if (const YAML::Node rms = f.optional_child(quality, "quality", "rms")) {
    c.rms = f.number(rms, "quality.rms");
  }
  const YAML::Node views = f.optional_child(quality, "quality", "views");
  if (!views) return;
  if (!views.IsSequence()) f.fail("quality.views", "expected a sequence of views");
  for (std::size_t i = 0; i < views.size(); ++i) {
    const std::string vp = cat("quality.views[", i, "]");
    const YAML::Node v = views[i];
    f.only_keys(v, vp, {"left", "right", "left_rms", "right_rms"});
    ViewError e;
    e.left = f.text(f.child(v, vp, "left"), vp + ".left");
    e.right = f.text(f.child(v, vp, "right"), vp + ".right");
    e.left_rms = f.number(f.child(v, vp, "left_rms"), vp + ".left_rms");
    e.right_rms = f.number(f.child(v, vp, "right_rms"), vp + ".right_rms");
    c.views.push_back(std::move(e));
  }
}

}  // namespace

StereoCalibration parse_calibration(const std::string& yaml, const std::string& file_name) {
  const yaml::Fields f(file_name);
  const YAML::Node root = f.parse(yaml);
  read_header(f, root, file_name);

  StereoCalibration c;
  c.date = f.text(f.child(root, "", "date"), "date");
  if (const YAML::Node source = f.optional_child(root, "", "source")) {
    c.source = f.text(source, "source");
  }
  const YAML::Node size = f.child(root, "", "image_size");
  f.only_keys(size, "image_size", {"width", "height"});
  c.width = f.integer(f.child(size, "image_size", "width"), "image_size.width");
  c.height = f.integer(f.child(size, "image_size", "height"), "image_size.height");
  const YAML::Node cameras = f.child(root, "", "cameras");
  f.only_keys(cameras, "cameras", {"left", "right"});
  c.left = read_camera(f, cameras, "left");
  c.right = read_camera(f, cameras, "right");
  read_geometry(f, root, c);
  read_quality(f, root, c);

  try {
    validate(c);
  } catch (const Error& e) {
    throw Error(cat(file_name, ": ", e.what()));
  }
  return c;
}

StereoCalibration load_calibration(const std::filesystem::path& file) {
  return parse_calibration(read_text_file(file), file.string());
}

std::string format_calibration(const StereoCalibration& c) {
  validate(c);
  YAML::Emitter out;
  out.SetDoublePrecision(17);  // every double reads back to the same bits
  out << YAML::Comment("Epipole stereo calibration (schema: docs/calibration.md)");
  out << YAML::BeginMap;
  out << YAML::Key << "format" << YAML::Value << kFormat;
  out << YAML::Key << "version" << YAML::Value << StereoCalibration::kVersion;
  out << YAML::Key << "date" << YAML::Value << YAML::DoubleQuoted << c.date;
  if (!c.source.empty()) {
    out << YAML::Key << "source" << YAML::Value << YAML::DoubleQuoted << c.source;
  }
  out << YAML::Key << "image_size" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key
      << "width" << YAML::Value << c.width << YAML::Key << "height" << YAML::Value << c.height
      << YAML::EndMap;
  out << YAML::Key << "cameras" << YAML::Value << YAML::BeginMap;
  emit_camera(out, "left", c.left);
  emit_camera(out, "right", c.right);
  out << YAML::EndMap;
  out << YAML::Key << "extrinsics" << YAML::Value << YAML::BeginMap;
  emit_matrix(out, "R", c.R);
  out << YAML::Key << "T" << YAML::Value << YAML::Flow << YAML::BeginSeq << c.T.x() << c.T.y()
      << c.T.z() << YAML::EndSeq;
  out << YAML::EndMap;
  out << YAML::Key << "rectification" << YAML::Value << YAML::BeginMap;
  emit_matrix(out, "R1", c.left.rectification);
  emit_matrix(out, "R2", c.right.rectification);
  emit_matrix(out, "P1", c.left.projection);
  emit_matrix(out, "P2", c.right.projection);
  emit_matrix(out, "Q", c.Q);
  out << YAML::EndMap;
  if (c.rms || !c.views.empty()) {
    out << YAML::Key << "quality" << YAML::Value << YAML::BeginMap;
    if (c.rms) out << YAML::Key << "rms" << YAML::Value << *c.rms;
    if (!c.views.empty()) {
      out << YAML::Key << "views" << YAML::Value << YAML::BeginSeq;
      for (const ViewError& v : c.views) {
        out << YAML::Flow << YAML::BeginMap;
        out << YAML::Key << "left" << YAML::Value << YAML::DoubleQuoted << v.left;
        out << YAML::Key << "right" << YAML::Value << YAML::DoubleQuoted << v.right;
        out << YAML::Key << "left_rms" << YAML::Value << v.left_rms;
        out << YAML::Key << "right_rms" << YAML::Value << v.right_rms;
        out << YAML::EndMap;
      }
      out << YAML::EndSeq;
    }
    out << YAML::EndMap;
  }
  out << YAML::EndMap;
  require(out.good(), "cannot format the calibration: ", out.GetLastError());
  return std::string(out.c_str()) + "\n";
}

void save_calibration(const std::filesystem::path& file, const StereoCalibration& calibration) {
  write_text_file_atomically(file, format_calibration(calibration));
}

Eigen::Matrix4d disparity_to_depth(const Eigen::Matrix<double, 3, 4>& P1,
                                   const Eigen::Matrix<double, 3, 4>& P2) {
  // In the rectified frames the right camera sits at t = (P2(0,3)/f, P2(1,3)/f, 0) from the
  // left. A point (X, Y, Z) of the left rectified frame is seen at u1 = f X / Z + cx1 and
  // u2 = f (X + tx) / Z + cx2, so d = u1 - u2 = -f tx / Z + cx1 - cx2, and
  // (u - cx1, v - cy1, f, (cx1 - cx2 - d) / tx) is (X, Y, Z, 1) times f / Z.
  Eigen::Matrix4d q = Eigen::Matrix4d::Zero();
  q(0, 0) = 1;
  q(1, 1) = 1;
  q(0, 3) = -P1(0, 2);
  q(1, 3) = -P1(1, 2);
  const bool horizontal = std::abs(P2(0, 3)) >= std::abs(P2(1, 3));
  if (horizontal) {
    const double tx = P2(0, 3) / P2(0, 0);
    q(2, 3) = P1(0, 0);
    q(3, 2) = -1 / tx;
    q(3, 3) = (P1(0, 2) - P2(0, 2)) / tx;
  } else {
    const double ty = P2(1, 3) / P2(1, 1);
    q(2, 3) = P1(1, 1);
    q(3, 2) = -1 / ty;
    q(3, 3) = (P1(1, 2) - P2(1, 2)) / ty;
  }
  return q;
}

std::string utc_now() {
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &utc);
  return text;
}

}  // namespace epipole::calib
