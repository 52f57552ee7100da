// Importing calibrations made by other tools: OpenCV's FileStorage output (YAML or XML) and
// ROS camera_info YAML files.
#include <yaml-cpp/yaml.h>

#include <cctype>
#include <fstream>
#include <optional>
#include <sstream>
#include <string_view>
#include <utility>

#include "epipole/calib/calibration.hpp"
#include "epipole/core/error.hpp"
#include "xml_reader.hpp"
#include "yaml_matrix.hpp"

namespace epipole::calib {

namespace {

// A matrix as FileStorage stores it, with where it came from.
struct StoredMatrix {
  int rows = 0;
  int cols = 0;
  std::vector<double> data;  // row-major
  std::string file;
  std::string key;

  template <int Rows, int Cols>
  Eigen::Matrix<double, Rows, Cols> fixed() const {
    require(rows == Rows && cols == Cols, file, ": ", key, ": expected a ", Rows, "x", Cols,
            " matrix, found ", rows, "x", cols);
    Eigen::Matrix<double, Rows, Cols> m;
    for (int r = 0; r < Rows; ++r) {
      for (int c = 0; c < Cols; ++c) m(r, c) = data[static_cast<std::size_t>(r * Cols + c)];
    }
    return m;
  }
  // A row or column vector.
  std::vector<double> vector() const {
    require(rows == 1 || cols == 1, file, ": ", key, ": expected a vector, found a ", rows, "x",
            cols, " matrix");
    return data;
  }
};

// dt of a single-channel matrix: "d", "f", "i", ... optionally with a count of 1.
bool single_channel(std::string dt) {
  if (!dt.empty() && dt[0] == '1') dt.erase(0, 1);
  return dt.size() == 1 && std::string_view("ucwsifdh").find(dt[0]) != std::string_view::npos;
}

std::vector<double> split_numbers(const std::string& text, const std::string& key,
                                  const std::string& file) {
  std::vector<double> values;
  std::size_t i = 0;
  while (i < text.size()) {
    while (i < text.size() && std::isspace(static_cast<unsigned char>(text[i]))) ++i;
    std::size_t end = i;
    while (end < text.size() && !std::isspace(static_cast<unsigned char>(text[end]))) ++end;
    if (end > i) {
      values.push_back(yaml::finite_number(text.substr(i, end - i), key, file));
    }
    i = end;
  }
  return values;
}

// One cv::FileStorage file, YAML or XML (told apart by the first character).
class StorageFile {
 public:
  explicit StorageFile(const std::filesystem::path& path) : file_(path.string()), yaml_(file_) {
    std::string text = yaml::read_file(path);
    const std::size_t first = text.find_first_not_of(" \t\r\n");
    xml_ = first != std::string::npos && text[first] == '<';
    if (xml_) {
      xml_root_ = detail::parse_xml(text, file_);
      require(xml_root_.name == "opencv_storage", file_, ": not an OpenCV FileStorage file (root <",
              xml_root_.name, "> instead of <opencv_storage>)");
    } else {
      // OpenCV writes the non-standard directive "%YAML:1.0"; yaml-cpp wants "%YAML 1.x".
      if (text.starts_with("%YAML")) {
        const std::size_t eol = text.find('\n');
        text.replace(0, eol == std::string::npos ? text.size() : eol, "");
      }
      root_ = yaml_.parse(text);
      require(root_.IsMap(), file_, ": not an OpenCV FileStorage file (no map of keys)");
    }
  }

  const std::string& name() const { return file_; }

  std::optional<StoredMatrix> matrix(const std::string& key) const {
    StoredMatrix m;
    m.file = file_;
    m.key = key;
    if (xml_) {
      const detail::XmlElement* e = xml_root_.child(key);
      if (e == nullptr) return std::nullopt;
      if (e->attribute("type_id") == "opencv-matrix") {
        const auto field = [&](const char* name) -> std::string {
          const detail::XmlElement* f = e->child(name);
          require(f != nullptr, file_, ": ", key, ": the matrix has no <", name, ">");
          return f->text;
        };
        m.rows = integer_text(field("rows"), key + ".rows");
        m.cols = integer_text(field("cols"), key + ".cols");
        check_dt(trim(field("dt")), key);
        m.data = split_numbers(field("data"), key, file_);
      } else {
        require(e->children.empty(), file_, ": ", key, ": expected a matrix or a list of numbers");
        m.data = split_numbers(e->text, key, file_);
        m.rows = 1;
        m.cols = static_cast<int>(m.data.size());
      }
    } else {
      const YAML::Node node = root_[key];
      if (!node.IsDefined() || node.IsNull()) return std::nullopt;
      if (node.IsMap()) {
        m.rows = yaml_.integer(yaml_.child(node, key, "rows"), key + ".rows");
        m.cols = yaml_.integer(yaml_.child(node, key, "cols"), key + ".cols");
        check_dt(yaml_.text(yaml_.child(node, key, "dt"), key + ".dt"), key);
        m.data = yaml_.numbers(yaml_.child(node, key, "data"), key + ".data");
      } else {
        m.data = yaml_.numbers(node, key);
        m.rows = 1;
        m.cols = static_cast<int>(m.data.size());
      }
    }
    require(
        m.rows >= 0 && m.cols >= 0 &&
            static_cast<std::size_t>(m.rows) * static_cast<std::size_t>(m.cols) == m.data.size(),
        file_, ": ", key, ": ", m.rows, "x", m.cols, " matrix with ", m.data.size(), " numbers");
    return m;
  }

  std::optional<int> integer(const std::string& key) const {
    if (xml_) {
      const detail::XmlElement* e = xml_root_.child(key);
      if (e == nullptr) return std::nullopt;
      return integer_text(e->text, key);
    }
    const YAML::Node node = root_[key];
    if (!node.IsDefined() || node.IsNull()) return std::nullopt;
    return yaml_.integer(node, key);
  }

 private:
  static std::string trim(const std::string& s) {
    const std::size_t a = s.find_first_not_of(" \t\r\n");
    if (a == std::string::npos) return {};
    const std::size_t b = s.find_last_not_of(" \t\r\n");
    return s.substr(a, b - a + 1);
  }
  int integer_text(const std::string& text, const std::string& key) const {
    return yaml_.integer(YAML::Node(trim(text)), key);
  }
  void check_dt(const std::string& dt, const std::string& key) const {
    require(single_channel(dt), file_, ": ", key, ": dt '", dt, "' is not a single-channel matrix");
  }

  std::string file_;
  yaml::Fields yaml_;
  bool xml_ = false;
  YAML::Node root_;
  detail::XmlElement xml_root_;
};

// OpenCV's distortion vector (k1 k2 p1 p2 [k3 [k4 k5 k6 [s1 s2 s3 s4 [tx ty]]]]) or ROS's D.
Distortion radial_tangential(const std::vector<double>& d, const std::string& where) {
  const std::size_t n = d.size();
  require(n == 0 || n == 4 || n == 5 || n == 8 || n == 12 || n == 14, where, ": ", n,
          " distortion coefficients (expected 4, 5, 8, 12 or 14)");
  for (std::size_t i = 5; i < n; ++i) {
    require(d[i] == 0, where, ": coefficient ", i + 1, " of ", n, " is ", d[i],
            ": the rational, thin-prism and tilted models are not supported "
            "(only radial-tangential k1 k2 p1 p2 k3)");
  }
  Distortion out;
  if (n >= 4) out = {d[0], d[1], d[2], d[3], n >= 5 ? d[4] : 0.0};
  return out;
}

CameraCalibration camera_from(const Eigen::Matrix3d& k, const Distortion& d,
                              const std::string& where) {
  const bool pinhole = std::abs(k(0, 1)) <= 1e-9 * std::abs(k(0, 0)) && k(1, 0) == 0 &&
                       k(2, 0) == 0 && k(2, 1) == 0 && k(2, 2) == 1;
  require(pinhole, where,
          ": the camera matrix must be [fx 0 cx; 0 fy cy; 0 0 1] (skew is not "
          "supported)");
  CameraCalibration c;
  c.camera.intrinsics = {k(0, 0), k(1, 1), k(0, 2), k(1, 2)};
  c.camera.distortion = d;
  return c;
}

// validate() names our schema's keys; an import speaks of the source's.
void validate_import(const StereoCalibration& c, const std::string& files,
                     std::initializer_list<std::pair<std::string_view, std::string_view>> names) {
  try {
    validate(c);
  } catch (const Error& e) {
    std::string message = e.what();
    for (const auto& [ours, theirs] : names) {
      if (message.starts_with(ours)) {
        message = std::string(theirs) + message.substr(ours.size());
        break;
      }
    }
    throw Error(cat(files, ": ", message));
  }
}

}  // namespace

StereoCalibration import_opencv_calibration(const std::filesystem::path& intrinsics,
                                            const std::filesystem::path& extrinsics, int width,
                                            int height) {
  std::vector<StorageFile> files;
  files.emplace_back(intrinsics);
  if (extrinsics != intrinsics) files.emplace_back(extrinsics);
  const std::string names =
      files.size() == 1 ? files[0].name() : files[0].name() + " and " + files[1].name();
  const auto get = [&](const std::string& key) -> StoredMatrix {
    for (const StorageFile& f : files) {
      if (auto m = f.matrix(key)) return *m;
    }
    throw Error(cat("missing key '", key, "' (looked in ", names, ")"));
  };
  const auto get_integer = [&](const std::string& key) -> std::optional<int> {
    for (const StorageFile& f : files) {
      if (auto v = f.integer(key)) return v;
    }
    return std::nullopt;
  };

  StereoCalibration c;
  if (width == 0 && height == 0) {
    const auto w = get_integer("image_width");
    const auto h = get_integer("image_height");
    require(w && h, "the image size is unknown: ", names,
            files.size() == 1 ? " records" : " record",
            " no image_width/image_height, so it must be given");
    width = *w;
    height = *h;
  }
  c.width = width;
  c.height = height;

  const StoredMatrix m1 = get("M1");
  const StoredMatrix m2 = get("M2");
  const StoredMatrix d1 = get("D1");
  const StoredMatrix d2 = get("D2");
  c.left = camera_from(m1.fixed<3, 3>(), radial_tangential(d1.vector(), d1.file + ": D1"),
                       m1.file + ": M1");
  c.right = camera_from(m2.fixed<3, 3>(), radial_tangential(d2.vector(), d2.file + ": D2"),
                        m2.file + ": M2");
  c.left.id = "left";
  c.right.id = "right";
  c.R = get("R").fixed<3, 3>();
  const StoredMatrix t = get("T");
  const std::vector<double> tv = t.vector();
  require(tv.size() == 3, t.file, ": T: expected 3 numbers, found ", tv.size());
  c.T = {tv[0], tv[1], tv[2]};
  c.left.rectification = get("R1").fixed<3, 3>();
  c.right.rectification = get("R2").fixed<3, 3>();
  c.left.projection = get("P1").fixed<3, 4>();
  c.right.projection = get("P2").fixed<3, 4>();
  std::optional<StoredMatrix> q;
  for (const StorageFile& f : files) {
    if (!q) q = f.matrix("Q");
  }
  c.Q = q ? q->fixed<4, 4>() : disparity_to_depth(c.left.projection, c.right.projection);
  c.date = utc_now();
  c.source = "import: opencv " + names;
  validate_import(c, names,
                  {{"image_size", "image size"},
                   {"cameras.left.K", "M1"},
                   {"cameras.right.K", "M2"},
                   {"cameras.left.distortion.coefficients", "D1"},
                   {"cameras.right.distortion.coefficients", "D2"},
                   {"extrinsics.R", "R"},
                   {"extrinsics.T", "T"},
                   {"rectification.", ""}});
  return c;
}

namespace {

struct RosCamera {
  int width = 0;
  int height = 0;
  std::string name;
  Eigen::Matrix3d K;
  Distortion distortion;
  Eigen::Matrix3d R;
  Eigen::Matrix<double, 3, 4> P;
};

Eigen::MatrixXd ros_matrix(const yaml::Fields& f, const YAML::Node& root, const char* key, int rows,
                           int cols) {
  const YAML::Node node = f.child(root, "", key);
  const int r = f.integer(f.child(node, key, "rows"), std::string(key) + ".rows");
  const int c = f.integer(f.child(node, key, "cols"), std::string(key) + ".cols");
  if (r != rows || c != cols) f.fail(key, cat("expected ", rows, "x", cols, ", found ", r, "x", c));
  const std::vector<double> data =
      f.numbers(f.child(node, key, "data"), std::string(key) + ".data");
  if (data.size() != static_cast<std::size_t>(rows * cols)) {
    f.fail(std::string(key) + ".data",
           cat("expected ", rows * cols, " numbers, found ", data.size()));
  }
  Eigen::MatrixXd m(rows, cols);
  for (int i = 0; i < rows; ++i) {
    for (int j = 0; j < cols; ++j) m(i, j) = data[static_cast<std::size_t>(i * cols + j)];
  }
  return m;
}

RosCamera read_ros(const std::filesystem::path& path) {
  const yaml::Fields f(path.string());
  const YAML::Node root = f.parse(yaml::read_file(path));
  f.require_map(root, "");
  RosCamera c;
  c.width = f.integer(f.child(root, "", "image_width"), "image_width");
  c.height = f.integer(f.child(root, "", "image_height"), "image_height");
  if (const YAML::Node name = f.optional_child(root, "", "camera_name")) {
    c.name = f.text(name, "camera_name");
  }
  c.K = ros_matrix(f, root, "camera_matrix", 3, 3);
  const std::string model = f.text(f.child(root, "", "distortion_model"), "distortion_model");
  const YAML::Node dnode = f.child(root, "", "distortion_coefficients");
  const std::vector<double> d =
      f.numbers(f.child(dnode, "distortion_coefficients", "data"), "distortion_coefficients.data");
  if (model == "plumb_bob" || model == "rational_polynomial") {
    c.distortion = radial_tangential(d, path.string() + ": distortion_coefficients");
  } else {
    f.fail("distortion_model", "'" + model +
                                   "' is not supported (plumb_bob, or rational_polynomial with "
                                   "k4 k5 k6 zero)");
  }
  c.R = ros_matrix(f, root, "rectification_matrix", 3, 3);
  c.P = ros_matrix(f, root, "projection_matrix", 3, 4);
  return c;
}

}  // namespace

StereoCalibration import_ros_calibration(const std::filesystem::path& left,
                                         const std::filesystem::path& right) {
  const RosCamera l = read_ros(left);
  const RosCamera r = read_ros(right);
  const std::string names = left.string() + " and " + right.string();
  require(l.width == r.width && l.height == r.height, names, ": image sizes differ (", l.width, "x",
          l.height, " and ", r.width, "x", r.height, ")");
  StereoCalibration c;
  c.width = l.width;
  c.height = l.height;
  c.left = camera_from(l.K, l.distortion, left.string() + ": camera_matrix");
  c.right = camera_from(r.K, r.distortion, right.string() + ": camera_matrix");
  c.left.id = l.name.empty() ? "left" : l.name;
  c.right.id = r.name.empty() ? "right" : r.name;
  c.left.rectification = l.R;
  c.right.rectification = r.R;
  c.left.projection = l.P;
  c.right.projection = r.P;
  // Rectified frames are parallel and the right one sits at t = (P2(0,3)/fx', P2(1,3)/fy', 0)
  // from the left: R2 x_right = R1 x_left + t, so R = R2^T R1 and T = R2^T t.
  require(r.P(0, 0) > 0 && r.P(1, 1) > 0, right.string(),
          ": projection_matrix: focal lengths must be > 0");
  const Eigen::Vector3d t(r.P(0, 3) / r.P(0, 0), r.P(1, 3) / r.P(1, 1), 0);
  c.R = r.R.transpose() * l.R;
  c.T = r.R.transpose() * t;
  c.Q = disparity_to_depth(c.left.projection, c.right.projection);
  c.date = utc_now();
  c.source = "import: ros " + names;
  validate_import(c, names,
                  {{"image_size", "image_width/image_height"},
                   {"cameras.left.K", "left camera_matrix"},
                   {"cameras.right.K", "right camera_matrix"},
                   {"cameras.left.distortion.coefficients", "left distortion_coefficients"},
                   {"cameras.right.distortion.coefficients", "right distortion_coefficients"},
                   {"extrinsics.T", "right projection_matrix (baseline)"},
                   {"extrinsics.R", "rectification matrices"},
                   {"rectification.R1", "left rectification_matrix"},
                   {"rectification.R2", "right rectification_matrix"},
                   {"rectification.P1", "left projection_matrix"},
                   {"rectification.P2", "right projection_matrix"},
                   {"rectification.Q", "projection matrices"}});
  return c;
}

}  // namespace epipole::calib
