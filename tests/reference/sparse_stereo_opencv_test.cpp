// Sparse stereo on real data against ground truth: on Middlebury Aloe (rectified, full size and
// 640x480) the share of matches within 1 px of aloeGT and their count; on the chessboard rig
// (the sample calibration, left01/right01 rectified as the firmware does) the 3-D distance
// between neighbouring chessboard corners (found by cv::findChessboardCorners) against the
// 25 mm squares.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "../calib/sample_calibration.hpp"
#include "epipole/firmware/sparse_points.hpp"
#include "epipole/firmware/stereo_rectification.hpp"
#include "epipole/vision/fast.hpp"
#include "epipole/vision/harris.hpp"
#include "epipole/vision/sparse_stereo.hpp"
#include "opencv_view.hpp"
#include "test_data.hpp"

namespace epipole::vision {
namespace {

cv::Mat read_gray(const char* name) {
  cv::Mat m = cv::imread(test::data_file(name).string(), cv::IMREAD_GRAYSCALE);
  EXPECT_FALSE(m.empty()) << name;
  return m;
}

std::vector<Corner> fast_corners(GrayView image) {
  FastDetector fast({.width = image.width(), .height = image.height(), .threshold = 20});
  const auto c = fast.detect(image);
  return {c.begin(), c.end()};
}

void aloe(int width, int height, int disparities) {
  cv::Mat left = read_gray("samples/aloeL.jpg");
  cv::Mat right = read_gray("samples/aloeR.jpg");
  cv::Mat truth;
  read_gray("samples/aloeGT.png").convertTo(truth, CV_32F);
  if (width != left.cols) {
    const double scale = static_cast<double>(width) / left.cols;
    cv::resize(left, left, {width, height}, 0, 0, cv::INTER_AREA);
    cv::resize(right, right, {width, height}, 0, 0, cv::INTER_AREA);
    cv::resize(truth, truth, {width, height}, 0, 0, cv::INTER_NEAREST);
    truth *= scale;
  }
  const auto l = fast_corners(test::view_of(left));
  const auto r = fast_corners(test::view_of(right));
  SparseStereoMatcher matcher({.width = width,
                               .height = height,
                               .max_disparity = disparities,
                               .max_corners = 10000,
                               .max_matches = 10000});
  const auto matches = matcher.match(test::view_of(left), l, test::view_of(right), r);
  int known = 0, within1 = 0, within05 = 0;
  double error = 0;
  for (const SparseMatch& m : matches) {
    const float t = truth.at<float>(static_cast<int>(m.yl), static_cast<int>(m.xl));
    if (t <= 0) continue;
    ++known;
    const double e = std::abs(static_cast<double>(m.disparity) - static_cast<double>(t));
    within1 += e <= 1 ? 1 : 0;
    within05 += e <= 0.5 ? 1 : 0;
    error += std::min(e, 10.0);
  }
  const double share = known > 0 ? static_cast<double>(within1) / known : 0;
  std::printf(
      "Aloe %dx%d, %d disparities: %zu / %zu FAST corners, %zu matches, %d with ground truth: "
      "%.1f %% within 1 px, %.1f %% within 0.5 px, mean error (capped at 10) %.2f px\n",
      width, height, disparities, l.size(), r.size(), matches.size(), known, 100 * share,
      100.0 * within05 / std::max(known, 1), error / std::max(known, 1));
  EXPECT_FALSE(matcher.truncated());
  EXPECT_GE(known, 1000);
  EXPECT_GE(share, 0.9);
}

TEST(SparseStereoReference, AloeFullSize) {
  aloe(1282, 1110, 256);
}
TEST(SparseStereoReference, Aloe640x480) {
  aloe(640, 480, 128);
}

TEST(SparseStereoReference, ChessboardSquaresIn3D) {
  const calib::StereoCalibration calibration = test::sample_calibration();
  firmware::StereoRectifiers rectifiers =
      firmware::make_stereo_rectifiers(calibration, SimdPath::reference);
  const cv::Mat raw_left = read_gray("samples/left01.jpg");
  const cv::Mat raw_right = read_gray("samples/right01.jpg");
  const GrayView left = rectifiers.left.rectify(test::view_of(raw_left));
  const GrayView right = rectifiers.right.rectify(test::view_of(raw_right));

  HarrisConfig harris{.width = 640, .height = 480};
  harris.min_distance = 5;
  harris.block_size = 5;
  HarrisDetector left_harris(harris), right_harris(harris);
  const auto lc = left_harris.detect(left);
  const auto rc = right_harris.detect(right);
  SparseStereoMatcher matcher({.width = 640, .height = 480, .max_disparity = 128});
  const auto matches = matcher.match(left, lc, right, rc);
  const calib::Triangulator triangulator(calibration);
  std::vector<firmware::SparsePoint> points(matches.size());
  points.resize(firmware::triangulate_matches(triangulator, matches, points));

  // The chessboard's inner corners on the rectified left image, and our point at each.
  const cv::Mat left_mat(480, 640, CV_8UC1, const_cast<std::uint8_t*>(left.row(0)),
                         static_cast<std::size_t>(left.stride()));
  std::vector<cv::Point2f> board;
  ASSERT_TRUE(cv::findChessboardCorners(left_mat, {9, 6}, board));
  cv::cornerSubPix(left_mat, board, {5, 5}, {-1, -1},
                   {cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 30, 0.01});
  const cv::Mat right_mat(480, 640, CV_8UC1, const_cast<std::uint8_t*>(right.row(0)),
                          static_cast<std::size_t>(right.stride()));
  std::vector<cv::Point2f> right_board;
  ASSERT_TRUE(cv::findChessboardCorners(right_mat, {9, 6}, right_board));
  cv::cornerSubPix(right_mat, right_board, {5, 5}, {-1, -1},
                   {cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 30, 0.01});

  // Each board corner takes the disparity of the match of a Harris corner within 3 px (Harris
  // peaks sit ~2 px off a chessboard's saddle points); it is right when it is within 2 px of
  // the difference of the two board corners.
  std::vector<Eigen::Vector3d> at(board.size(), Eigen::Vector3d::Constant(NAN));
  int matched = 0, right_disparity = 0;
  for (std::size_t i = 0; i < board.size(); ++i) {
    for (const firmware::SparsePoint& p : points) {
      if (std::hypot(p.xl - board[i].x, p.yl - board[i].y) > 3.0f) continue;
      ++matched;
      if (std::abs(p.disparity - (board[i].x - right_board[i].x)) > 2.0f) break;
      ++right_disparity;
      at[i] = triangulator.point(board[i].x, board[i].y, p.disparity);
      break;
    }
  }
  std::vector<double> lengths;
  for (int row = 0; row < 6; ++row) {
    for (int col = 0; col < 9; ++col) {
      const std::size_t i = static_cast<std::size_t>(row * 9 + col);
      for (const std::size_t j : {i + 1, i + 9}) {
        if ((j == i + 1 && col == 8) || j >= board.size()) continue;
        if (!at[i].allFinite() || !at[j].allFinite()) continue;
        lengths.push_back((at[i] - at[j]).norm());
      }
    }
  }
  double sum = 0, worst = 0;
  for (const double l : lengths) {
    sum += l;
    worst = std::max(worst, std::abs(l - 0.025));
  }
  const double mean = lengths.empty() ? 0 : sum / static_cast<double>(lengths.size());
  std::printf(
      "chessboard left01/right01 rectified, %zu / %zu Harris corners, %zu matches: %d of 54 "
      "board corners matched, %d of them within 2 px of the board's disparity; %zu "
      "neighbour pairs: mean %.2f mm (squares 25 mm), worst off by %.2f mm\n",
      lc.size(), rc.size(), matches.size(), matched, right_disparity, lengths.size(), 1000 * mean,
      1000 * worst);
  EXPECT_GE(matched, 20);
  EXPECT_GE(3 * right_disparity, 2 * matched) << "a repetitive pattern: some matches are off";
  EXPECT_GE(lengths.size(), 10u);
  EXPECT_NEAR(mean, 0.025, 0.025 * 0.05);
}

}  // namespace
}  // namespace epipole::vision
