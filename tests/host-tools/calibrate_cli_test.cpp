// `epipole calibrate` and `epipole rectify` as a user runs them, on the real chessboard pairs.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>
#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "epipole/calib/calibration.hpp"
#include "epipole/core/image_io.hpp"
#include "epipole/tools/opencv_calibration.hpp"
#include "run_tool.hpp"
#include "test_data.hpp"
#include "test_paths.hpp"

namespace {

namespace fs = std::filesystem;

using Result = epipole::test::ToolResult;
using epipole::test::line_count;
using epipole::test::run_tool;
using epipole::test::source_dir;

std::string quoted(const fs::path& p) {
  return "'" + p.string() + "'";
}

fs::path samples() {
  return epipole::test::data_file("samples/left01.jpg").parent_path();
}

fs::path work_dir() {
  // One folder per test process: ctest may run this program's tests side by side.
  const fs::path dir =
      fs::path(::testing::TempDir()) / ("epipole-calibrate-cli-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir;
}

std::string read(const fs::path& file) {
  std::ifstream in(file);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// One calibration of the 13 pairs, shared by the tests that need its outputs.
struct Calibration {
  Result result;
  fs::path rig, report, preview;
};

const Calibration& calibration() {
  static const Calibration c = [] {
    Calibration out;
    out.rig = work_dir() / "rig.yaml";
    out.report = work_dir() / "report.json";
    out.preview = work_dir() / "preview.png";
    out.result = run_tool("calibrate --left " + quoted(samples() / "left[0-9]*.jpg") + " --right " +
                          quoted(samples() / "right[0-9]*.jpg") +
                          " --board chessboard:9x6 --square 0.025 -o " + quoted(out.rig) +
                          " --report " + quoted(out.report) + " --preview " + quoted(out.preview));
    return out;
  }();
  return c;
}

TEST(CalibrateCli, CalibratesTheThirteenPairs) {
  const Calibration& c = calibration();
  ASSERT_EQ(c.result.exit_code, 0) << c.result.out;
  EXPECT_EQ(line_count(c.result.out), 1) << c.result.out;
  EXPECT_NE(c.result.out.find("calibrated 13 of 13 pairs"), std::string::npos) << c.result.out;

  const auto report = nlohmann::json::parse(read(c.report));
  // The design brief's baseline, OpenCV's stereo_calib sample on the same pairs: RMS 0.634 px,
  // rectified row error 0.185 px (tests/reference/calibration_opencv_test.cpp re-measures it).
  const double rms = report["rms"].get<double>();
  EXPECT_LT(rms, 0.634);
  EXPECT_GT(rms, 0.2);
  const auto& row = report["rectified_row_error"];
  EXPECT_LT(row["mean"].get<double>(), 0.185);
  EXPECT_GT(row["mean"].get<double>(), 0.0);
  EXPECT_LE(row["median"].get<double>(), row["p90"].get<double>());
  EXPECT_LE(row["p90"].get<double>(), row["max"].get<double>());
  EXPECT_EQ(row["points"], 13 * 54);
  EXPECT_EQ(report["image_size"]["width"], 640);
  EXPECT_EQ(report["image_size"]["height"], 480);
  EXPECT_EQ(report["pairs"], 13);
  EXPECT_EQ(report["views_used"], 13);
  EXPECT_TRUE(report["rejected"].empty()) << report["rejected"];
  ASSERT_EQ(report["views"].size(), 13u);
  double sum_squares = 0;
  for (const auto& v : report["views"]) {
    EXPECT_GT(v["left_rms"].get<double>(), 0.0);
    EXPECT_GT(v["right_rms"].get<double>(), 0.0);
    sum_squares +=
        std::pow(v["left_rms"].get<double>(), 2) + std::pow(v["right_rms"].get<double>(), 2);
  }
  // The overall RMS is the per-view errors pooled (every view has 54 corners).
  EXPECT_NEAR(std::sqrt(sum_squares / 26), rms, 1e-6);
  // left02/right02 is the one view far from the others (about 1.2 px against 0.2-0.6).
  ASSERT_EQ(report["outliers"].size(), 1u) << report["outliers"];
  EXPECT_NE(report["outliers"][0]["left"].get<std::string>().find("left02.jpg"), std::string::npos);
  EXPECT_NEAR(report["baseline"].get<double>(), 0.0834, 0.002);  // metres

  const std::string rig = read(c.rig);
  EXPECT_NE(rig.find("format: epipole-stereo-calibration"), std::string::npos) << rig;
  EXPECT_NE(rig.find("version: 1"), std::string::npos);
  const epipole::GrayImage preview = epipole::load_gray(c.preview);
  EXPECT_EQ(preview.width(), 1280);
  EXPECT_EQ(preview.height(), 480);
}

TEST(CalibrateCli, DroppingOutliersLowersTheRms) {
  const fs::path rig = work_dir() / "rig-dropped.yaml";
  const fs::path report_file = work_dir() / "report-dropped.json";
  const Result r = run_tool("calibrate --left " + quoted(samples() / "left[0-9]*.jpg") +
                            " --right " + quoted(samples() / "right[0-9]*.jpg") +
                            " --board chessboard:9x6 --square 0.025 --drop-outliers -o " +
                            quoted(rig) + " --report " + quoted(report_file));
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto report = nlohmann::json::parse(read(report_file));
  EXPECT_EQ(report["views_used"], 12);
  EXPECT_LT(report["rms"].get<double>(), report["rms_before_dropping_outliers"].get<double>());
}

TEST(CalibrateCli, RectifiesAPairWithTheProducedFile) {
  const Calibration& c = calibration();
  ASSERT_EQ(c.result.exit_code, 0) << c.result.out;
  const fs::path left = work_dir() / "L.png";
  const fs::path right = work_dir() / "R.png";
  const fs::path pair = work_dir() / "pair.png";
  for (const char* kernels : {"ref", "auto"}) {
    const Result r = run_tool(
        std::string("--kernels ") + kernels + " rectify " + quoted(samples() / "left01.jpg") + " " +
        quoted(samples() / "right01.jpg") + " --calib " + quoted(c.rig) + " --out-left " +
        quoted(left) + " --out-right " + quoted(right) + " --preview " + quoted(pair));
    ASSERT_EQ(r.exit_code, 0) << r.out;
    EXPECT_EQ(line_count(r.out), 1) << r.out;
  }
  const epipole::GrayImage l = epipole::load_gray(left);
  const epipole::GrayImage rr = epipole::load_gray(right);
  const epipole::GrayImage original = epipole::load_gray(samples() / "left01.jpg");
  EXPECT_EQ(l.width(), 640);
  EXPECT_EQ(l.height(), 480);
  EXPECT_EQ(rr.width(), 640);
  int changed = 0;
  for (int y = 0; y < 480; ++y) {
    for (int x = 0; x < 640; ++x) changed += l(x, y) != original(x, y);
  }
  EXPECT_GT(changed, 640 * 480 / 2);  // the lens distortion is strong: most pixels move
  EXPECT_EQ(epipole::load_gray(pair).width(), 1280);

  const Result json =
      run_tool("rectify " + quoted(samples() / "left01.jpg") + " " +
               quoted(samples() / "right01.jpg") + " --calib " + quoted(c.rig) + " --out-left " +
               quoted(left) + " --out-right " + quoted(right) + " --json");
  ASSERT_EQ(json.exit_code, 0) << json.out;
  const auto summary = nlohmann::json::parse(json.out);
  EXPECT_EQ(summary["image_size"]["width"], 640);
  EXPECT_EQ(summary["left"], left.string());
  EXPECT_TRUE(summary["preview"].is_null());
  EXPECT_GE(summary["ms"].get<double>(), 0.0);
}

// The rig in OpenCV's and ROS's files, and back: OpenCV's files of the imported calibration are
// the exported ones to the byte; ROS's give the same rig (R and T recovered, to rounding).
TEST(CalibrateCli, ExportsForOpenCvAndRosAndImportsThemBack) {
  const Calibration& c = calibration();
  ASSERT_EQ(c.result.exit_code, 0) << c.result.out;
  const epipole::calib::StereoCalibration rig = epipole::calib::load_calibration(c.rig);
  const fs::path first = work_dir() / "export-opencv-1";
  epipole::tools::export_opencv_calibration(rig, first);
  const fs::path again = work_dir() / "export-opencv-2";
  const fs::path ros = work_dir() / "export-ros";
  const fs::path imported = work_dir() / "rig-from-opencv.yaml";
  const Result r = run_tool("calibrate --from-opencv " + quoted(first / "intrinsics.yml") + " " +
                            quoted(first / "extrinsics.yml") + " -o " + quoted(imported) +
                            " --export-opencv " + quoted(again) + " --export-ros " + quoted(ros));
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_EQ(line_count(r.out), 3) << r.out;
  EXPECT_EQ(read(again / "intrinsics.yml"), read(first / "intrinsics.yml"));
  EXPECT_EQ(read(again / "extrinsics.yml"), read(first / "extrinsics.yml"));

  const Result json = run_tool("calibrate --from-opencv " + quoted(first / "intrinsics.yml") + " " +
                               quoted(first / "extrinsics.yml") + " -o " + quoted(imported) +
                               " --export-ros " + quoted(ros) + " --json");
  ASSERT_EQ(json.exit_code, 0) << json.out;
  const auto summary = nlohmann::json::parse(json.out);
  EXPECT_EQ(summary["output"], imported.string());
  EXPECT_EQ(summary["image_size"]["height"], 480);
  ASSERT_EQ(summary["exported"].size(), 1u);
  EXPECT_EQ(summary["exported"][0]["format"], "ros");
  EXPECT_EQ(summary["exported"][0]["files"][0], (ros / "left.yaml").string());

  const fs::path from_ros = work_dir() / "rig-from-ros.yaml";
  const Result back = run_tool("calibrate --from-ros " + quoted(ros / "left.yaml") + " " +
                               quoted(ros / "right.yaml") + " -o " + quoted(from_ros));
  ASSERT_EQ(back.exit_code, 0) << back.out;
  const epipole::calib::StereoCalibration got = epipole::calib::load_calibration(from_ros);
  EXPECT_EQ(got.left.camera_matrix(), rig.left.camera_matrix());
  EXPECT_EQ(got.right.projection, rig.right.projection);
  EXPECT_LT((got.R - rig.R).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((got.T - rig.T).cwiseAbs().maxCoeff(), 1e-12);

  const Result bad = run_tool("calibrate --from-ros " + quoted(ros / "left.yaml") + " " +
                              quoted(ros / "right.yaml") + " -o " + quoted(from_ros) +
                              " --export-ros " + quoted(c.rig / "inside-a-file"));
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_EQ(line_count(bad.out), 2) << "the import's line, then the error\n" << bad.out;
  EXPECT_NE(bad.out.find("inside-a-file"), std::string::npos) << bad.out;
}

TEST(CalibrateCli, ReportsRejectedViews) {
  // Five pairs; in the last the right image shows no board.
  const fs::path dir = work_dir() / "rejected";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const char* ids[] = {"01", "03", "04", "06", "08"};
  for (int i = 0; i < 5; ++i) {
    const std::string n = std::to_string(i);
    fs::create_symlink(samples() / (std::string("left") + ids[i] + ".jpg"),
                       dir / ("l" + n + ".jpg"));
    if (i < 4) {
      fs::create_symlink(samples() / (std::string("right") + ids[i] + ".jpg"),
                         dir / ("r" + n + ".jpg"));
    }
  }
  epipole::GrayImage blank(640, 480);
  for (int y = 0; y < 480; ++y) {
    for (int x = 0; x < 640; ++x) blank(x, y) = static_cast<std::uint8_t>(100 + x % 7);
  }
  epipole::save_image(dir / "r4.png", epipole::GrayView(blank.view()));
  const fs::path report_file = dir / "report.json";
  const Result r = run_tool("calibrate --left " + quoted(dir / "l*") + " --right " +
                            quoted(dir / "r*") + " --board chessboard:9x6 --square 0.025 -o " +
                            quoted(dir / "rig.yaml") + " --report " + quoted(report_file));
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_NE(r.out.find("calibrated 4 of 5 pairs (1 rejected"), std::string::npos) << r.out;
  const auto report = nlohmann::json::parse(read(report_file));
  ASSERT_EQ(report["rejected"].size(), 1u);
  EXPECT_NE(report["rejected"][0]["right"].get<std::string>().find("r4.png"), std::string::npos);
  EXPECT_EQ(report["rejected"][0]["reason"], "board not found in the right image");
  EXPECT_EQ(report["views"].size(), 4u);
}

void expect_one_line_error(const std::string& arguments, const std::string& names) {
  SCOPED_TRACE(arguments);
  const Result r = run_tool(arguments);
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_EQ(line_count(r.out), 1) << r.out;
  EXPECT_NE(r.out.find(names), std::string::npos) << r.out;
}

TEST(CalibrateCli, BadArgumentsAreOneLineErrors) {
  const std::string left = " --left " + quoted(samples() / "left0[1-4].jpg");
  const std::string right = " --right " + quoted(samples() / "right0[1-4].jpg");
  const std::string out = " -o " + quoted(work_dir() / "bad.yaml");
  expect_one_line_error("calibrate --left " + quoted(samples() / "nothing*.png") + right + out,
                        "matches no file");
  expect_one_line_error("calibrate" + left + right + " --board circles:4x11" + out, "--board");
  expect_one_line_error("calibrate" + left + right + " --board chessboard:9by6" + out, "--board");
  expect_one_line_error("calibrate" + left + right + " --board chessboard:7x7" + out, "square");
  expect_one_line_error("calibrate" + left + right + " --square -1" + out, "--square");
  expect_one_line_error(
      "calibrate" + left + " --right " + quoted(samples() / "right0[1-3].jpg") + out, "pairs");
  // An image of another size than the others (left.jpg is 612x459).
  expect_one_line_error("calibrate --left " + quoted(samples() / "left.jpg") + " --right " +
                            quoted(samples() / "right01.jpg") + out,
                        "right01.jpg: image is 640x480 but");
  expect_one_line_error("calibrate --left " + quoted(samples() / "left01.jpg") + " --right " +
                            quoted(samples() / "right01.jpg") + out,
                        "only 1 of 1 pairs");
  expect_one_line_error("calibrate --from-opencv " + quoted(samples() / "intrinsics.yml") + " " +
                            quoted(samples() / "intrinsics.yml") + out,
                        "--size WIDTHxHEIGHT");
  expect_one_line_error("calibrate --from-opencv " + quoted(samples() / "intrinsics.yml") + " " +
                            quoted(samples() / "intrinsics.yml") + " --size 640x480" + out,
                        "missing key 'R'");
  expect_one_line_error("calibrate --from-opencv " + quoted(samples() / "intrinsics.yml") + " " +
                            quoted(samples() / "intrinsics.yml") + " --size 640by480" + out,
                        "--size");
  const Result no_output = run_tool("calibrate" + left + right);
  EXPECT_NE(no_output.exit_code, 0);
  EXPECT_FALSE(fs::exists(work_dir() / "bad.yaml"));
}

TEST(CalibrateCli, CorruptCalibrationFilesAreOneLineErrors) {
  const Calibration& c = calibration();
  ASSERT_EQ(c.result.exit_code, 0) << c.result.out;
  const std::string images =
      "rectify " + quoted(samples() / "left01.jpg") + " " + quoted(samples() / "right01.jpg");
  const std::string outputs = " --out-left " + quoted(work_dir() / "x-l.png") + " --out-right " +
                              quoted(work_dir() / "x-r.png");
  const auto write = [](const fs::path& file, const std::string& text) {
    std::ofstream(file) << text;
    return file;
  };
  const std::string rig = read(c.rig);
  const fs::path garbage = write(work_dir() / "garbage.yaml", "\x01\x02 not: [yaml");
  expect_one_line_error(images + " --calib " + quoted(garbage) + outputs, "garbage.yaml");
  const fs::path truncated = write(work_dir() / "truncated.yaml", rig.substr(0, rig.size() / 2));
  expect_one_line_error(images + " --calib " + quoted(truncated) + outputs, "truncated.yaml");
  std::string no_q = rig;
  no_q.erase(no_q.find("  Q:"), no_q.find("quality:") - no_q.find("  Q:"));
  const fs::path missing = write(work_dir() / "missing-q.yaml", no_q);
  expect_one_line_error(images + " --calib " + quoted(missing) + outputs,
                        "missing key 'rectification.Q'");
  std::string nan = rig;
  nan.replace(nan.find("[0, 0, 1]"), 9, "[0, .nan, 1]");
  const fs::path non_finite = write(work_dir() / "nan.yaml", nan);
  expect_one_line_error(images + " --calib " + quoted(non_finite) + outputs, "cameras.left.K");
  // Images of another size than the calibration's.
  expect_one_line_error("rectify " + quoted(samples() / "left.jpg") + " " +
                            quoted(samples() / "right01.jpg") + " --calib " + quoted(c.rig) +
                            outputs,
                        "left.jpg: image is 612x459");
}

}  // namespace

// board/sim/chessboard-rig.yaml is this calibration, made by the same command: a change of the
// calibration code that moves the result must regenerate it (the command is in the file).
TEST(CalibrateCli, TheSimulatedBoardsRigIsThisCalibration) {
  const Calibration& c = calibration();
  ASSERT_EQ(c.result.exit_code, 0) << c.result.out;
  const auto fresh = epipole::calib::load_calibration(c.rig);
  const auto committed = epipole::calib::load_calibration(fs::path(source_dir()) / "board" / "sim" /
                                                          "chessboard-rig.yaml");
  EXPECT_TRUE(fresh.Q.isApprox(committed.Q, 1e-6)) << fresh.Q << "\n" << committed.Q;
  EXPECT_TRUE(fresh.left.camera_matrix().isApprox(committed.left.camera_matrix(), 1e-6));
  EXPECT_TRUE(fresh.right.camera_matrix().isApprox(committed.right.camera_matrix(), 1e-6));
  EXPECT_TRUE(fresh.T.isApprox(committed.T, 1e-6));
  EXPECT_TRUE(fresh.left.rectification.isApprox(committed.left.rectification, 1e-6));
}
