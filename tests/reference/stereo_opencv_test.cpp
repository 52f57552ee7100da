// Dense disparity on Middlebury Aloe against its ground truth, beside OpenCV's StereoSGBM and
// StereoBM with the same disparity range, measured in the same run: quality mode must have at
// most SGBM's bad2, fast mode at most StereoBM's.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

#include "epipole/vision/stereo.hpp"
#include "opencv_view.hpp"
#include "test_data.hpp"

namespace epipole::vision {
namespace {

struct Scores {
  double bad1 = 0;        // share of pixels with ground truth that are missing or off by > 1 px
  double bad2 = 0;        // ... by > 2 px
  double density = 0;     // share of pixels with ground truth that have a disparity
  double mean_error = 0;  // over those, in pixels
};

// disparity: CV_16S, x16, anything < 0 invalid; truth: CV_32F in pixels, 0 unknown.
Scores score(const cv::Mat& disparity, const cv::Mat& truth) {
  long known = 0, valid = 0, bad1 = 0, bad2 = 0;
  double error_sum = 0;
  for (int y = 0; y < truth.rows; ++y) {
    for (int x = 0; x < truth.cols; ++x) {
      const float t = truth.at<float>(y, x);
      if (t <= 0) continue;
      ++known;
      const int d = disparity.at<std::int16_t>(y, x);
      if (d < 0) {
        ++bad1;
        ++bad2;
        continue;
      }
      ++valid;
      const double e = std::abs(d / 16.0 - static_cast<double>(t));
      error_sum += e;
      bad1 += e > 1 ? 1 : 0;
      bad2 += e > 2 ? 1 : 0;
    }
  }
  const auto k = static_cast<double>(known);
  return {static_cast<double>(bad1) / k, static_cast<double>(bad2) / k,
          static_cast<double>(valid) / k, valid > 0 ? error_sum / static_cast<double>(valid) : 0.0};
}

void print(const std::string& name, const Scores& s) {
  std::printf("  %-26s bad1 %5.1f %%  bad2 %5.1f %%  density %5.1f %%  mean error %5.2f px\n",
              name.c_str(), 100 * s.bad1, 100 * s.bad2, 100 * s.density, s.mean_error);
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
