// Dense disparity on Middlebury Aloe against its ground truth, beside OpenCV's StereoSGBM and
// StereoBM with the same disparity range, measured in the same run: quality mode must have at
// most SGBM's bad2, fast mode at most StereoBM's. And against the figures stored in
// stereo_quality_baseline.json (as OpenCV's own stereo regression test keeps its own:
// stereo_scoring.hpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

#include "epipole/vision/speckle_filter.hpp"
#include "stereo_scoring.hpp"
#include "test_data.hpp"

namespace epipole::vision {
namespace {

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
  const Scores filled =
      score(ours(a.left, a.right, StereoMethod::sgm, disparities, 1, 64), a.truth);
  print("epipole sgm, holes <= 64", filled);
  StereoConfig occlusions;
  occlusions.max_disparity = disparities;
  occlusions.fill_occlusions = true;
  const Scores sgm_occlusions = score(ours(a.left, a.right, occlusions), a.truth);
  print("epipole sgm, occlusions", sgm_occlusions);
  occlusions.method = StereoMethod::bm;
  const Scores bm_occlusions = score(ours(a.left, a.right, occlusions), a.truth);
  print("epipole bm, occlusions", bm_occlusions);
  // The depth-quality issue's aim: at most 0.8x SGBM's bad2, with the occlusions filled.
  EXPECT_LE(sgm_occlusions.bad2, 0.8 * cv_sgbm.bad2);
  EXPECT_GE(sgm_occlusions.density, cv_sgbm.density);
  EXPECT_LE(sgm.bad2, cv_sgbm.bad2);
  EXPECT_LE(bm.bad2, cv_bm.bad2);
  const std::string scene = "aloe-" + std::to_string(a.left.cols) + "x" +
                            std::to_string(a.left.rows) + "-" + std::to_string(disparities);
  check_baseline(scene, "sgm", sgm);
  check_baseline(scene, "bm", bm);
  check_baseline(scene, "sgm-holes64", filled);
  check_baseline(scene, "sgm-occlusions", sgm_occlusions);
  check_baseline(scene, "bm-occlusions", bm_occlusions);
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

// The speckle filter against OpenCV's filterSpeckles on a real disparity map: StereoSGBM's of
// Aloe without its own speckle filter, every invalid value made -16 (OpenCV's newVal). Ours
// removes regions of fewer than min_size pixels, OpenCV's those of at most maxSpeckleSize.
TEST(StereoOpenCV, SpeckleFilterIsOpenCVsFilterSpeckles) {
  const Aloe a = aloe(640, 480);
  const auto sgbm = cv::StereoSGBM::create(0, 112, 5, 200, 800, 1, 63, 10, 0, 0);
  cv::Mat raw;
  sgbm->compute(a.left, a.right, raw);
  raw.setTo(kInvalidDisparity, raw < 0);
  for (const int min_size : {20, 100}) {
    for (const int range : {1, 2}) {
      cv::Mat opencv = raw.clone();
      cv::filterSpeckles(opencv, kInvalidDisparity, min_size - 1, range * kDisparityScale);
      cv::Mat mine = raw.clone();
      SpeckleFilter filter(mine.cols, mine.rows, min_size, range);
      filter.apply(ImageView<std::int16_t>(mine.ptr<std::int16_t>(), mine.cols, mine.rows,
                                           static_cast<std::ptrdiff_t>(mine.step1())),
                   SimdPath::neon);
      EXPECT_EQ(cv::countNonZero(mine != opencv), 0)
          << "min_size " << min_size << " range " << range;
      EXPECT_GT(cv::countNonZero(mine != raw), 1000) << "speckles were removed";
    }
  }
}

TEST(StereoOpenCV, AloeFullSize) {
  compare(1282, 1110, 224);
}
TEST(StereoOpenCV, Aloe640x480) {
  compare(640, 480, 112);
}

}  // namespace
}  // namespace epipole::vision
