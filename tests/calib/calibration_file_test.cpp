// The calibration file: exact round trips, and every kind of bad input is an Error that names
// the file and the key — never a partial calibration.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

#include "epipole/calib/calibration.hpp"
#include "epipole/core/error.hpp"
#include "sample_calibration.hpp"

namespace epipole::calib {
namespace {

constexpr const char* kName = "rig.yaml";

void expect_same(const StereoCalibration& a, const StereoCalibration& b) {
  EXPECT_EQ(a.width, b.width);
  EXPECT_EQ(a.height, b.height);
  for (const auto& [x, y] : {std::pair{&a.left, &b.left}, std::pair{&a.right, &b.right}}) {
    EXPECT_EQ(x->id, y->id);
    EXPECT_EQ(x->camera_matrix(), y->camera_matrix());
    const Distortion& d = x->camera.distortion;
    const Distortion& e = y->camera.distortion;
    EXPECT_EQ(d.k1, e.k1);
    EXPECT_EQ(d.k2, e.k2);
    EXPECT_EQ(d.p1, e.p1);
    EXPECT_EQ(d.p2, e.p2);
    EXPECT_EQ(d.k3, e.k3);
    EXPECT_EQ(x->rectification, y->rectification);
    EXPECT_EQ(x->projection, y->projection);
  }
  EXPECT_EQ(a.R, b.R);
  EXPECT_EQ(a.T, b.T);
  EXPECT_EQ(a.Q, b.Q);
  EXPECT_EQ(a.rms, b.rms);
  ASSERT_EQ(a.views.size(), b.views.size());
  for (std::size_t i = 0; i < a.views.size(); ++i) {
    EXPECT_EQ(a.views[i].left, b.views[i].left);
    EXPECT_EQ(a.views[i].right, b.views[i].right);
    EXPECT_EQ(a.views[i].left_rms, b.views[i].left_rms);
    EXPECT_EQ(a.views[i].right_rms, b.views[i].right_rms);
  }
  EXPECT_EQ(a.date, b.date);
  EXPECT_EQ(a.source, b.source);
}

// The message of the Error that parsing `yaml` throws ("" if it does not throw).
std::string parse_error(const std::string& yaml) {
  try {
    parse_calibration(yaml, kName);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

// A valid file changed by `edit`.
std::string edited(const std::function<void(YAML::Node&)>& edit) {
  YAML::Node root = YAML::Load(format_calibration(test::sample_calibration()));
  edit(root);
  YAML::Emitter out;
  out << root;
  return out.c_str();
}

void expect_error(const std::string& yaml, const std::string& key, const std::string& also = "") {
  const std::string message = parse_error(yaml);
  ASSERT_FALSE(message.empty()) << "no error for a file with a bad " << key;
  EXPECT_EQ(message.rfind(std::string(kName) + ": ", 0), 0u) << message;
  EXPECT_NE(message.find(key), std::string::npos) << "does not name " << key << ": " << message;
  if (!also.empty()) {
    EXPECT_NE(message.find(also), std::string::npos) << message;
  }
  EXPECT_EQ(message.find('\n'), std::string::npos) << "not one line: " << message;
}

TEST(CalibrationFile, RoundTripIsExact) {
  const StereoCalibration original = test::sample_calibration();
  const std::string text = format_calibration(original);
  expect_same(parse_calibration(text, kName), original);
  // Without the optional parts.
  StereoCalibration bare = original;
  bare.rms.reset();
  bare.views.clear();
  bare.source.clear();
  const std::string bare_text = format_calibration(bare);
  EXPECT_EQ(bare_text.find("quality"), std::string::npos);
  expect_same(parse_calibration(bare_text, kName), bare);
}

TEST(CalibrationFile, SaveAndLoad) {
  const std::filesystem::path file = std::filesystem::path(::testing::TempDir()) / "calib-rig.yaml";
  const StereoCalibration original = test::sample_calibration();
  save_calibration(file, original);
  expect_same(load_calibration(file), original);
  // No temporary file is left beside it.
  for (const auto& entry : std::filesystem::directory_iterator(file.parent_path())) {
    EXPECT_EQ(entry.path().string().find("calib-rig.yaml.tmp"), std::string::npos);
  }
  std::filesystem::remove(file);
}

TEST(CalibrationFile, FileErrorsNameTheFile) {
  const std::string missing = ::testing::TempDir() + "no-such-rig.yaml";
  try {
    load_calibration(missing);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(missing), std::string::npos) << e.what();
  }
  const std::string unwritable = ::testing::TempDir() + "no-such-folder/rig.yaml";
  try {
    save_calibration(unwritable, test::sample_calibration());
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(unwritable), std::string::npos) << e.what();
  }
}

TEST(CalibrationFile, MalformedYaml) {
  expect_error("format: epipole-stereo-calibration\nversion: [1\n", "line");
  expect_error("{ unclosed", "malformed YAML");
  expect_error("", "not a calibration file");
  expect_error("just a string", "not a calibration file");
  expect_error("- a\n- list\n", "not a calibration file");
  expect_error("format: something-else\nversion: 1\n", "format", "not an Epipole");
  expect_error(edited([](YAML::Node& r) { r["version"] = 2; }), "version", "newer");
  expect_error(edited([](YAML::Node& r) { r["version"] = "one"; }), "version", "not an integer");
  expect_error(edited([](YAML::Node& r) { r["version"] = 0; }), "version");
  expect_error(edited([](YAML::Node& r) { r["colour"] = "blue"; }), "colour", "unknown key");
  expect_error(edited([](YAML::Node& r) { r["cameras"]["left"]["serial"] = 7; }),
               "cameras.left.serial", "unknown key");
}

TEST(CalibrationFile, EveryMissingKeyIsNamed) {
  const std::vector<std::vector<std::string>> keys = {
      {"format"},
      {"version"},
      {"date"},
      {"image_size"},
      {"image_size", "width"},
      {"image_size", "height"},
      {"cameras"},
      {"cameras", "left"},
      {"cameras", "right"},
      {"cameras", "left", "id"},
      {"cameras", "left", "K"},
      {"cameras", "right", "distortion"},
      {"cameras", "right", "distortion", "model"},
      {"cameras", "right", "distortion", "coefficients"},
      {"extrinsics"},
      {"extrinsics", "R"},
      {"extrinsics", "T"},
      {"rectification"},
      {"rectification", "R1"},
      {"rectification", "R2"},
      {"rectification", "P1"},
      {"rectification", "P2"},
      {"rectification", "Q"},
  };
  for (const auto& path : keys) {
    std::string dotted;
    for (const auto& k : path) dotted += (dotted.empty() ? "" : ".") + k;
    SCOPED_TRACE(dotted);
    const std::string yaml = edited([&](YAML::Node& root) {
      // Walk with fresh handles: assigning a yaml-cpp node rebinds rather than re-pointing.
      std::vector<YAML::Node> chain{root};
      for (std::size_t i = 0; i + 1 < path.size(); ++i) chain.push_back(chain.back()[path[i]]);
      chain.back().remove(path.back());
    });
    expect_error(yaml, dotted, path.front() == "format" ? "" : "missing key");
  }
}

TEST(CalibrationFile, WrongMatrixSizes) {
  expect_error(edited([](YAML::Node& r) { r["cameras"]["left"]["K"].remove(2); }), "cameras.left.K",
               "3x3");
  expect_error(edited([](YAML::Node& r) { r["cameras"]["right"]["K"][1].push_back(0); }),
               "cameras.right.K", "row 2");
  expect_error(edited([](YAML::Node& r) { r["rectification"]["P1"][0].remove(3); }),
               "rectification.P1", "3x4");
  expect_error(
      edited([](YAML::Node& r) { r["rectification"]["Q"].push_back(r["rectification"]["Q"][0]); }),
      "rectification.Q", "4x4");
  expect_error(edited([](YAML::Node& r) { r["extrinsics"]["T"].push_back(1.0); }), "extrinsics.T",
               "3 numbers");
  expect_error(edited([](YAML::Node& r) { r["extrinsics"]["R"] = 1.0; }), "extrinsics.R", "3x3");
  expect_error(edited([](YAML::Node& r) {
                 r["cameras"]["left"]["distortion"]["coefficients"].push_back(0.0);
               }),
               "cameras.left.distortion.coefficients", "expected 5");
}

TEST(CalibrationFile, NonFiniteAndNonNumbers) {
  for (const char* bad : {".nan", ".inf", "-.inf", ".NaN", "nan", "1e999", "abc", "0x10"}) {
    SCOPED_TRACE(bad);
    expect_error(edited([&](YAML::Node& r) { r["rectification"]["R1"][1][2] = bad; }),
                 "rectification.R1[1][2]", bad);
    expect_error(edited([&](YAML::Node& r) { r["extrinsics"]["T"][0] = bad; }), "extrinsics.T[0]");
    expect_error(edited([&](YAML::Node& r) { r["quality"]["rms"] = bad; }), "quality.rms");
  }
  expect_error(edited([](YAML::Node& r) { r["cameras"]["left"]["K"][0][0] = YAML::Node(); }),
               "cameras.left.K[0][0]");
}

TEST(CalibrationFile, ValuesThatAreNotACalibration) {
  expect_error(edited([](YAML::Node& r) { r["image_size"]["width"] = 0; }), "image_size");
  expect_error(edited([](YAML::Node& r) { r["image_size"]["height"] = 40000; }), "image_size");
  expect_error(edited([](YAML::Node& r) { r["cameras"]["left"]["K"][0][0] = -500.0; }),
               "cameras.left.K", "focal");
  expect_error(edited([](YAML::Node& r) { r["cameras"]["left"]["K"][0][1] = 0.5; }),
               "cameras.left.K", "skew");
  expect_error(edited([](YAML::Node& r) { r["cameras"]["right"]["K"][2][2] = 2.0; }),
               "cameras.right.K");
  expect_error(
      edited([](YAML::Node& r) { r["cameras"]["left"]["distortion"]["model"] = "fisheye"; }),
      "cameras.left.distortion.model", "fisheye");
  expect_error(edited([](YAML::Node& r) { r["extrinsics"]["R"][0][0] = 1.5; }), "extrinsics.R",
               "rotation");
  expect_error(edited([](YAML::Node& r) { r["rectification"]["R1"][0][0] = 0.9; }),
               "rectification.R1", "rotation");
  expect_error(edited([](YAML::Node& r) {
                 for (int i = 0; i < 3; ++i) r["extrinsics"]["T"][i] = 0.0;
               }),
               "extrinsics.T", "zero");
  expect_error(edited([](YAML::Node& r) { r["rectification"]["P2"][0][3] = 0.0; }),
               "rectification.P2", "baseline");
  expect_error(edited([](YAML::Node& r) { r["rectification"]["P1"][2][2] = 0.0; }),
               "rectification.P1");
  // Rectification from another calibration: R2 R is not R1.
  expect_error(edited([](YAML::Node& r) {
                 YAML::Node rotation = YAML::Load("[[1, 0, 0], [0, 1, 0], [0, 0, 1]]");
                 r["rectification"]["R2"] = rotation;
               }),
               "rectification.R2", "R1");
  expect_error(edited([](YAML::Node& r) { r["quality"]["rms"] = -1.0; }), "quality.rms");
  expect_error(edited([](YAML::Node& r) { r["quality"]["views"][1]["left_rms"] = -0.5; }),
               "quality.views[1]");
  expect_error(edited([](YAML::Node& r) { r["quality"]["views"][0].remove("right"); }),
               "quality.views[0].right", "missing key");
}

TEST(CalibrationFile, NeverHalfLoaded) {
  // A failed load leaves the caller's calibration as it was: load_calibration returns a
  // complete value or throws, so there is no state in between to observe.
  StereoCalibration kept = test::sample_calibration();
  const std::string bad = edited([](YAML::Node& r) { r["rectification"].remove("Q"); });
  EXPECT_THROW(kept = parse_calibration(bad, kName), Error);
  expect_same(kept, test::sample_calibration());
}

TEST(CalibrationFile, FormatRefusesAnInvalidCalibration) {
  StereoCalibration c = test::sample_calibration();
  c.left.camera.intrinsics.fx = std::nan("");
  EXPECT_THROW(format_calibration(c), Error);
  const std::filesystem::path file = std::filesystem::path(::testing::TempDir()) / "invalid.yaml";
  EXPECT_THROW(save_calibration(file, c), Error);
  EXPECT_FALSE(std::filesystem::exists(file));
}

TEST(CalibrationFile, DisparityToDepthIsTheSampleQ) {
  const StereoCalibration c = test::sample_calibration();
  const Eigen::Matrix4d q = disparity_to_depth(c.left.projection, c.right.projection);
  EXPECT_LT((q - c.Q).cwiseAbs().maxCoeff(), 1e-9) << q;
}

}  // namespace
}  // namespace epipole::calib
