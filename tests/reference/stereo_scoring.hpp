#pragma once

// What the dense-stereo reference tests share: our matcher and OpenCV's on cv::Mat images, the
// ground-truth figures (vision/disparity_quality.hpp), a printed row, and the check against the
// stored figures of tests/reference/stereo_quality_baseline.json: bad2 may not grow, nor the
// density drop, nor the valid pixels more than 2 px off grow, by more than 0.1 point. After a
// deliberate change, `EPIPOLE_UPDATE_QUALITY_BASELINE=1` on the test program writes the new figures
// there.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <string>

#include "epipole/vision/disparity_quality.hpp"
#include "epipole/vision/stereo.hpp"
#include "opencv_view.hpp"
#include "test_paths.hpp"

namespace epipole::vision {

using Scores = DisparityQuality;

// disparity: CV_16S, x16, below 0 missing; truth: CV_32F in pixels, 0 unknown; mask: empty, or
// CV_8U, the pixels to count nonzero.
inline Scores score(const cv::Mat& disparity, const cv::Mat& truth, const cv::Mat& mask = {}) {
  const ImageView<const std::int16_t> d(disparity.ptr<std::int16_t>(), disparity.cols,
                                        disparity.rows, static_cast<int>(disparity.step1()));
  const ImageView<const float> t(truth.ptr<float>(), truth.cols, truth.rows,
                                 static_cast<int>(truth.step1()));
  if (mask.empty()) return disparity_quality(d, t);
  return disparity_quality(d, t, test::view_of(mask));
}

inline void print(const std::string& name, const Scores& s) {
  std::printf(
      "  %-26s bad1 %5.1f %%  bad2 %5.1f %%  bad4 %5.1f %%  D1 %5.1f %%  density %5.1f %%  "
      "mean error %5.2f px\n",
      name.c_str(), 100 * s.bad1, 100 * s.bad2, 100 * s.bad4, 100 * s.d1, 100 * s.density,
      s.mean_error);
}

// The stored figures of a scene and method: bad2 may not grow, the density not drop, the valid
// pixels more than 2 px off not grow, by more than this (the results are exact on every kernel
// path, so any change is a change of code).
constexpr double kBaselineTolerance = 0.001;

inline std::filesystem::path baseline_file() {
  return std::filesystem::path(test::source_dir()) / "tests/reference/stereo_quality_baseline.json";
}

inline void check_baseline(const std::string& scene, const std::string& method, const Scores& s) {
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
  // The pixels with a disparity more than 2 px off: bad2 without the missing ones. A change that
  // buys density with wrong pixels shows here.
  const auto wrong = [](double bad2, double density) { return bad2 - (1 - density); };
  EXPECT_LE(wrong(s.bad2, s.density),
            wrong(b["bad2"].get<double>(), b["density"].get<double>()) + kBaselineTolerance)
      << scene << " " << method << ": more valid pixels more than 2 px off than the baseline";
}

// config's size is the images'.
inline cv::Mat ours(const cv::Mat& left, const cv::Mat& right, StereoConfig config) {
  config.width = left.cols;
  config.height = left.rows;
  StereoMatcher matcher(config);
  const ImageView<const std::int16_t> d =
      matcher.compute(test::view_of(left), test::view_of(right));
  cv::Mat out(d.height(), d.width(), CV_16S);
  for (int y = 0; y < d.height(); ++y) {
    std::copy_n(d.row(y), d.width(), out.ptr<std::int16_t>(y));
  }
  return out;
}

inline cv::Mat ours(const cv::Mat& left, const cv::Mat& right, StereoMethod method, int disparities,
                    int threads = 1, int hole_fill = 0) {
  StereoConfig config;
  config.threads = threads;
  config.hole_fill = hole_fill;
  config.max_disparity = disparities;
  config.method = method;
  return ours(left, right, config);
}

inline cv::Mat opencv_sgbm(const cv::Mat& left, const cv::Mat& right, int disparities) {
  constexpr int kBlock = 5;
  const auto sgbm =
      cv::StereoSGBM::create(0, disparities, kBlock, 8 * kBlock * kBlock, 32 * kBlock * kBlock, 1,
                             63, 10, 100, 2, cv::StereoSGBM::MODE_SGBM);
  cv::Mat out;
  sgbm->compute(left, right, out);
  return out;
}

inline cv::Mat opencv_bm(const cv::Mat& left, const cv::Mat& right, int disparities) {
  const auto bm = cv::StereoBM::create(disparities, 15);
  bm->setUniquenessRatio(10);
  bm->setSpeckleWindowSize(100);
  bm->setSpeckleRange(2);
  bm->setDisp12MaxDiff(1);
  cv::Mat out;
  bm->compute(left, right, out);
  return out;
}

}  // namespace epipole::vision
