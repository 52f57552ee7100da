// OpenCV's stereo calibration files, read by cv::FileStorage (YAML, XML or JSON, told apart by
// their first bytes as OpenCV does), checked here key by key so that every refusal names the
// file and the key. Bytes OpenCV 4.6 cannot take without crashing are refused before it sees
// them, and it parses each file first in a child process, which its hangs and crashes end.
#include <opencv2/core.hpp>
#include <pugixml.hpp>

#include <Eigen/Core>
#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <exception>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "epipole/calib/imported_calibration.hpp"
#include "epipole/core/error.hpp"
#include "epipole/core/text_file.hpp"
#include "epipole/tools/opencv_calibration.hpp"
#include "trial_in_child.hpp"

namespace epipole::tools {

namespace {

using calib::StereoCalibration;

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
    return Eigen::Map<const Eigen::Matrix<double, Rows, Cols, Eigen::RowMajor>>(data.data());
  }
  // A row or column vector.
  const std::vector<double>& vector() const {
    require(rows == 1 || cols == 1, file, ": ", key, ": expected a vector, found a ", rows, "x",
            cols, " matrix");
    return data;
  }
};

// dt of a single-channel matrix: "d", "f", "i", ... optionally with a count of 1.
bool single_channel(std::string_view dt) {
  if (dt.starts_with('1')) dt.remove_prefix(1);
  return dt.size() == 1 && std::string_view("ucwsifdh").find(dt[0]) != std::string_view::npos;
}

// What went wrong, without OpenCV's source location. Parse errors carry "NAME(LINE): message"
// (NAME is empty when reading from memory) in one of the exception's fields.
std::string reason(const cv::Exception& e) {
  for (const std::string& part : {e.err, e.func}) {
    const std::size_t open = part.find('(');
    const std::size_t close = part.find("): ");
    if (open == std::string::npos || close == std::string::npos || close <= open + 1) continue;
    const std::string line = part.substr(open + 1, close - open - 1);
    bool digits = true;
    for (const char c : line) digits = digits && std::isdigit(static_cast<unsigned char>(c)) != 0;
    if (digits) return cat("line ", line, ": ", part.substr(close + 3));
  }
  return e.err;
}

// Told apart as OpenCV does, by the first byte.
const char* syntax_of(const std::string& text) {
  switch (text[0]) {
    case '%':
      return "YAML";
    case '<':
      return "XML";
    case '{':
      return "JSON";
    default:
      return "file";
  }
}

// One cv::FileStorage file.
class StorageFile {
 public:
  explicit StorageFile(const std::filesystem::path& path) : name_(path.string()) {
    const std::string text = read_text_file(path);
    require(text.find_first_not_of(" \t\r\n") != std::string::npos, name_, ": the file is empty");
    // OpenCV reads a file in memory as a C string: a NUL would end it early, the rest silently
    // dropped. No YAML, XML or JSON file holds one.
    const std::size_t nul = text.find('\0');
    require(nul == std::string::npos, name_, ": not a text file (a NUL byte at offset ", nul, ")");
    if (text[0] == '<') check_xml(text);
    try_parsing(text);
    try {
      storage_.open(text, cv::FileStorage::READ | cv::FileStorage::MEMORY);
    } catch (const cv::Exception& e) {
      if (e.code == cv::Error::StsBadArg) {
        throw Error(cat(name_,
                        ": not an OpenCV FileStorage file (YAML starts with %YAML, XML with "
                        "<?xml, JSON with {)"));
      }
      throw Error(cat(name_, ": malformed ", syntax_of(text), " (", reason(e), ")"));
    } catch (const std::exception& e) {
      // OpenCV's parsers let some malformed input escape as standard exceptions (a string
      // length_error from a garbled YAML key, found by calibration_fuzz).
      throw Error(cat(name_, ": malformed ", syntax_of(text), " (", e.what(), ")"));
    }
    require(storage_.isOpened(), name_, ": OpenCV cannot read the file");
  }

  const std::string& name() const { return name_; }

  std::optional<StoredMatrix> matrix(const std::string& key) const {
    return guarded(key, [&]() -> std::optional<StoredMatrix> {
      const cv::FileNode node = storage_[key];
      if (node.empty() || node.isNone()) return std::nullopt;
      StoredMatrix m;
      m.file = name_;
      m.key = key;
      if (node.isMap()) {  // !!opencv-matrix, <KEY type_id="opencv-matrix">
        m.rows = integer_of(field(node, key, "rows"), key + ".rows");
        m.cols = integer_of(field(node, key, "cols"), key + ".cols");
        const cv::FileNode dt = field(node, key, "dt");
        const std::string type = dt.isString() ? dt.string() : std::string();
        require(single_channel(type), name_, ": ", key, ": dt '", type,
                "' is not a single-channel matrix");
        m.data = numbers(field(node, key, "data"), key + ".data");
      } else {  // a list of numbers
        m.data = numbers(node, key);
        m.rows = 1;
        m.cols = static_cast<int>(m.data.size());
      }
      require(
          m.rows >= 0 && m.cols >= 0 &&
              static_cast<std::size_t>(m.rows) * static_cast<std::size_t>(m.cols) == m.data.size(),
          name_, ": ", key, ": ", m.rows, "x", m.cols, " matrix with ", m.data.size(), " numbers");
      return m;
    });
  }

  std::optional<int> integer(const std::string& key) const {
    return guarded(key, [&]() -> std::optional<int> {
      const cv::FileNode node = storage_[key];
      if (node.empty() || node.isNone()) return std::nullopt;
      return integer_of(node, key);
    });
  }

 private:
  // OpenCV 4.6's XML parser crashes on some malformed files (`<?xml version=` alone, found by
  // calibration_fuzz): pugixml, the XML library the host tool links for cascades, sees first
  // that the file is well-formed.
  void check_xml(const std::string& text) const {
    pugi::xml_document document;
    const pugi::xml_parse_result parsed = document.load_buffer(text.data(), text.size());
    if (parsed) return;
    const auto end = text.begin() + std::clamp<std::ptrdiff_t>(parsed.offset, 0, text.size());
    throw Error(cat(name_, ": malformed XML (line ", 1 + std::count(text.begin(), end, '\n'), ": ",
                    parsed.description(), ")"));
  }

  // OpenCV 4.6's parsers loop forever on some malformed YAML and recurse without limit on deep
  // nesting (opencv/opencv#29939): tried in a child first. A real calibration file takes
  // well under a millisecond.
  void try_parsing(const std::string& text) const {
    constexpr std::chrono::seconds limit{5};
    const auto parse = [&] {
      const cv::FileStorage storage(text, cv::FileStorage::READ | cv::FileStorage::MEMORY);
    };
    switch (trial_in_child(parse, limit)) {
      case TrialOutcome::finished:
        return;
      case TrialOutcome::timed_out:
        throw Error(cat(name_, ": malformed ", syntax_of(text),
                        " (OpenCV's reader was still parsing it after ", limit.count(), " s)"));
      case TrialOutcome::crashed:
        throw Error(
            cat(name_, ": malformed ", syntax_of(text), " (OpenCV's reader crashed on it)"));
    }
  }

  // OpenCV's own complaints about a node, as an Error naming the file and the key.
  template <typename Read>
  auto guarded(const std::string& key, Read read) const -> decltype(read()) {
    try {
      return read();
    } catch (const cv::Exception& e) {
      throw Error(cat(name_, ": ", key, ": ", reason(e)));
    } catch (const Error&) {
      throw;
    } catch (const std::exception& e) {
      throw Error(cat(name_, ": ", key, ": ", e.what()));
    }
  }
  cv::FileNode field(const cv::FileNode& matrix, const std::string& key, const char* name) const {
    const cv::FileNode f = matrix[name];
    require(!f.empty() && !f.isNone(), name_, ": ", key, ": the matrix has no ", name);
    return f;
  }
  int integer_of(const cv::FileNode& node, const std::string& key) const {
    require(node.isInt(), name_, ": ", key, ": expected an integer");
    return static_cast<int>(node);
  }
  std::vector<double> numbers(const cv::FileNode& node, const std::string& key) const {
    require(node.isSeq(), name_, ": ", key, ": expected a matrix or a list of numbers");
    std::vector<double> values;
    values.reserve(node.size());
    for (const cv::FileNode& element : node) {
      require(element.isInt() || element.isReal(), name_, ": ", key, ": element ",
              values.size() + 1, " is not a number");
      const double value = element.isInt() ? static_cast<double>(static_cast<int>(element))
                                           : static_cast<double>(element);
      require(std::isfinite(value), name_, ": ", key, ": element ", values.size() + 1,
              " is not a finite number");
      values.push_back(value);
    }
    return values;
  }

  std::string name_;
  cv::FileStorage storage_;
};

}  // namespace

StereoCalibration import_opencv_calibration(const std::filesystem::path& intrinsics,
                                            const std::filesystem::path& extrinsics, int width,
                                            int height) {
  std::vector<StorageFile> files;
  files.emplace_back(intrinsics);
  if (extrinsics != intrinsics) files.emplace_back(extrinsics);
  const std::string names =
      files.size() == 1 ? files[0].name() : files[0].name() + " and " + files[1].name();
  const auto find = [&](const std::string& key) -> std::optional<StoredMatrix> {
    for (const StorageFile& f : files) {
      if (auto m = f.matrix(key)) return m;
    }
    return std::nullopt;
  };
  const auto get = [&](const std::string& key) -> StoredMatrix {
    if (auto m = find(key)) return *m;
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

  const auto camera = [&](const char* k, const char* d) {
    const StoredMatrix m = get(k);
    const StoredMatrix coefficients = get(d);
    return calib::pinhole_camera(
        m.fixed<3, 3>(),
        calib::radial_tangential_distortion(coefficients.vector(), cat(coefficients.file, ": ", d)),
        cat(m.file, ": ", k));
  };
  c.left = camera("M1", "D1");
  c.right = camera("M2", "D2");
  c.left.id = "left";
  c.right.id = "right";
  c.R = get("R").fixed<3, 3>();
  const StoredMatrix t = get("T");
  const std::vector<double>& tv = t.vector();
  require(tv.size() == 3, t.file, ": T: expected 3 numbers, found ", tv.size());
  c.T = {tv[0], tv[1], tv[2]};
  c.left.rectification = get("R1").fixed<3, 3>();
  c.right.rectification = get("R2").fixed<3, 3>();
  c.left.projection = get("P1").fixed<3, 4>();
  c.right.projection = get("P2").fixed<3, 4>();
  const std::optional<StoredMatrix> q = find("Q");
  c.Q = q ? q->fixed<4, 4>() : calib::disparity_to_depth(c.left.projection, c.right.projection);
  c.date = calib::utc_now();
  c.source = "import: opencv " + names;
  calib::validate_imported(c, names,
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

}  // namespace epipole::tools
