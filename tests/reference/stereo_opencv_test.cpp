// Dense disparity on Middlebury Aloe against its ground truth, beside OpenCV's StereoSGBM and
// StereoBM with the same disparity range, measured in the same run: quality mode must have at
// most SGBM's bad2, fast mode at most StereoBM's. And against the figures stored in
// stereo_quality_baseline.json (as OpenCV's own stereo regression test keeps its own): a
// failure when bad2 grows or the density drops by more than 0.1 point. After a deliberate
// change, `EPIPOLE_UPDATE_QUALITY_BASELINE=1 build/host/tests/stereo_reference_tests` writes
// the new figures there.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

#include "epipole/vision/disparity_quality.hpp"
#include "epipole/vision/stereo.hpp"
#include "opencv_view.hpp"
#include "test_data.hpp"
#include "test_paths.hpp"

namespace epipole::vision {
namespace {

using Scores = DisparityQuality;

// disparity: CV_16S, x16, below 0 missing; truth: CV_32F in pixels, 0 unknown.
Scores score(const cv::Mat& disparity, const cv::Mat& truth) {
  const ImageView<const std::int16_t> d(disparity.ptr<std::int16_t>(), disparity.cols,
                                        disparity.rows, static_cast<int>(disparity.step1()));
  const ImageView<const float> t(truth.ptr<float>(), truth.cols, truth.rows,
                                 static_cast<int>(truth.step1()));
  return disparity_quality(d, t);
}

void print(const std::string& name, const Scores& s) {
  std::printf(
      "  %-26s bad1 %5.1f %%  bad2 %5.1f %%  bad4 %5.1f %%  D1 %5.1f %%  density %5.1f %%  "
      "mean error %5.2f px\n",
      name.c_str(), 100 * s.bad1, 100 * s.bad2, 100 * s.bad4, 100 * s.d1, 100 * s.density,
      s.mean_error);
}

// The stored figures of a scene and method: bad2 may not grow, the density not drop, by more
// than this (the results are exact on every kernel path, so any change is a change of code).
constexpr double kBaselineTolerance = 0.001;

std::filesystem::path baseline_file() {
  return std::filesystem::path(test::source_dir()) / "tests/reference/stereo_quality_baseline.json";
}

void check_baseline(const std::string& scene, const std::string& method, const Scores& s) {
  const std::filesystem::path file = baseline_file();
  nlohmann::json baseline = nlohmann::json::object();
  if (std::ifstream in(file); in) baseline = nlohmann::json::parse(in);
  if (std::getenv("EPIPOLE_UPDATE_QUALITY_BASELINE") != nullptr) {
    baseline[scene][method] = {{"bad2", s.bad2}, {"density", s.density}, {"d1", s.d1}};
    std::ofstream(file) << baseline.dump(2) << "\n";
    std::printf("  %s %s: baseline written to %s\n", scene.c_str(), method.c_str(), file.c_str());
    return;
  }
  ASSERT_TRUE(baseline.contains(scene) && baseline[scene].contains(method))
      << "no baseline for " << scene << " " << method << " in " << file;
  const nlohmann::json& b = baseline[scene][method];
  EXPECT_LE(s.bad2, b["bad2"].get<double>() + kBaselineTolerance)
      << scene << " " << method << ": bad2 grew from the baseline";
  EXPECT_GE(s.density, b["density"].get<double>() - kBaselineTolerance)
      << scene << " " << method << ": density dropped from the baseline";
}

cv::Mat ours(const cv::Mat& left, const cv::Mat& right, StereoMethod method, int disparities,
             int threads = 1) {
  StereoConfig config;
  config.threads = threads;
  config.width = left.cols;
  config.height = left.rows;
  config.max_disparity = disparities;
  config.method = method;
  StereoMatcher matcher(config);
  const ImageView<const std::int16_t> d =
      matcher.compute(test::view_of(left), test::view_of(right));
  cv::Mat out(d.height(), d.width(), CV_16S);
  for (int y = 0; y < d.height(); ++y) {
    std::copy_n(d.row(y), d.width(), out.ptr<std::int16_t>(y));
  }
  return out;
}

cv::Mat opencv_sgbm(const cv::Mat& left, const cv::Mat& right, int disparities) {
  constexpr int kBlock = 5;
  const auto sgbm =
      cv::StereoSGBM::create(0, disparities, kBlock, 8 * kBlock * kBlock, 32 * kBlock * kBlock, 1,
                             63, 10, 100, 2, cv::StereoSGBM::MODE_SGBM);
  cv::Mat out;
  sgbm->compute(left, right, out);
  return out;
}

cv::Mat opencv_bm(const cv::Mat& left, const cv::Mat& right, int disparities) {
  const auto bm = cv::StereoBM::create(disparities, 15);
  bm->setUniquenessRatio(10);
  bm->setSpeckleWindowSize(100);
  bm->setSpeckleRange(2);
  bm->setDisp12MaxDiff(1);
  cv::Mat out;
  bm->compute(left, right, out);
  return out;
}

struct Aloe {
  cv::Mat left, right, truth;
};

Aloe aloe(int width, int height) {
  Aloe a;
  a.left = cv::imread(test::data_file("samples/aloeL.jpg").string(), cv::IMREAD_GRAYSCALE);
  a.right = cv::imread(test::data_file("samples/aloeR.jpg").string(), cv::IMREAD_GRAYSCALE);
  cv::Mat truth = cv::imread(test::data_file("samples/aloeGT.png").string(), cv::IMREAD_GRAYSCALE);
  EXPECT_FALSE(a.left.empty() || a.right.empty() || truth.empty());
  truth.convertTo(a.truth, CV_32F);
  if (width != a.left.cols || height != a.left.rows) {
    const double scale = static_cast<double>(width) / a.left.cols;
    cv::resize(a.left, a.left, {width, height}, 0, 0, cv::INTER_AREA);
    cv::resize(a.right, a.right, {width, height}, 0, 0, cv::INTER_AREA);
    cv::resize(a.truth, a.truth, {width, height}, 0, 0, cv::INTER_NEAREST);
    a.truth *= scale;  // disparities are horizontal distances
  }
  return a;
}

void compare(int width, int height, int disparities) {
  const Aloe a = aloe(width, height);
  const Scores sgm = score(ours(a.left, a.right, StereoMethod::sgm, disparities), a.truth);
  const Scores bm = score(ours(a.left, a.right, StereoMethod::bm, disparities), a.truth);
  const Scores cv_sgbm = score(opencv_sgbm(a.left, a.right, disparities), a.truth);
  const Scores cv_bm = score(opencv_bm(a.left, a.right, disparities), a.truth);
  std::printf("Aloe %dx%d, %d disparities:\n", a.left.cols, a.left.rows, disparities);
  print("epipole sgm", sgm);
  print("OpenCV StereoSGBM", cv_sgbm);
  print("epipole bm", bm);
  print("OpenCV StereoBM", cv_bm);
  EXPECT_LE(sgm.bad2, cv_sgbm.bad2);
  EXPECT_LE(bm.bad2, cv_bm.bad2);
  const std::string scene = "aloe-" + std::to_string(a.left.cols) + "x" +
                            std::to_string(a.left.rows) + "-" + std::to_string(disparities);
  check_baseline(scene, "sgm", sgm);
  check_baseline(scene, "bm", bm);
}

// Quality mode on 2 threads: the second stripe starts its vertical paths kWarmupRows above its
// first row, so its first rows differ a little from one thread's; this measures by how much.
TEST(StereoOpenCV, QualityModeOnTwoThreads) {
  const Aloe a = aloe(640, 480);
  const cv::Mat one = ours(a.left, a.right, StereoMethod::sgm, 112, 1);
  const cv::Mat two = ours(a.left, a.right, StereoMethod::sgm, 112, 2);
  int differ = 0, first_row = a.left.rows, last_row = -1;
  for (int y = 0; y < one.rows; ++y) {
    for (int x = 0; x < one.cols; ++x) {
      if (one.at<std::int16_t>(y, x) == two.at<std::int16_t>(y, x)) continue;
      ++differ;
      first_row = std::min(first_row, y);
      last_row = std::max(last_row, y);
    }
  }
  const Scores s1 = score(one, a.truth);
  const Scores s2 = score(two, a.truth);
  std::printf(
      "Aloe 640x480, 112 disparities, sgm: 2 threads differ from 1 in %d pixels (%.2f %%), "
      "rows %d..%d; bad2 %.2f %% vs %.2f %%\n",
      differ, 100.0 * differ / (one.rows * one.cols), first_row, last_row, 100 * s1.bad2,
      100 * s2.bad2);
  EXPECT_LT(differ, one.rows * one.cols / 50);
  EXPECT_NEAR(s1.bad2, s2.bad2, 0.002);
  EXPECT_EQ(cv::countNonZero(ours(a.left, a.right, StereoMethod::bm, 112, 2) !=
                             ours(a.left, a.right, StereoMethod::bm, 112, 1)),
            0)
      << "block matching does not depend on the thread count";
}

TEST(StereoOpenCV, AloeFullSize) {
  compare(1282, 1110, 224);
}
TEST(StereoOpenCV, Aloe640x480) {
  compare(640, 480, 112);
}

}  // namespace
}  // namespace epipole::vision
