// Harris against cv::cornerHarris and cv::goodFeaturesToTrack on the real images of the data
// sets.
//
// Response tolerance. R = (a c - b^2) - k (a + c)^2 cancels: near R = 0 its terms are large and
// its value small, so a pure ratio |ours - cv| / |cv| is meaningless there. Every term is
// bounded by trace^2 = (a + c)^2 (a c <= trace^2 / 4, b^2 <= a c), so float rounding errors are
// measured against scale = max(|R|, k trace^2). Two checks, per pixel, borders included (both
// sides use BORDER_REFLECT_101):
//   1. Against the exact value (integer Sobel and window sums from OpenCV, R in long double):
//      |ours - exact| <= 1e-5 * scale. Ours rounds only in its last, float step.
//   2. Against cv::cornerHarris: |ours - cv| <= 1e-4 * scale + 1e-5 * max|R|. The second term
//      is OpenCV's own error floor: its box filter keeps float running sums along each row,
//      whose rounding error is absolute, about 1e-7 of the largest sums met; on weak pixels
//      next to strong edges cv::cornerHarris itself is off the exact value by up to 1.6e-4 *
//      scale (measured: graf1, left01, block 3 and 5), but never by more than 1e-6 * max|R|.
//   The test prints the pure ratio |ours - cv| / scale and how many pixels exceed 1e-4 in it.
//
// Corner sets. Where the two responses differ in the last bits, a comparison of two nearly
// equal R (the quality threshold, a 3x3 neighbour, a stronger corner within min_distance, the
// last corner kept under max_corners) could go either way. Such a corner is a near-tie when
// OpenCV's R there is within the response tolerance above of one of those competing values;
// at most kTieAllowance corners per comparison may differ, and each must be a near-tie. None
// occurred: on the three images the sets, and their order, are the same.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <set>
#include <utility>

#include "epipole/vision/harris.hpp"
#include "opencv_view.hpp"
#include "real_images.hpp"
#include "test_data.hpp"

namespace epipole::vision {
namespace {

using test::RealImage;

constexpr double kK = 0.04;

// The exact response and trace: integer Sobel (CV_16S), products and window sums of integers
// in double (exact below 2^53), then R in long double.
struct Exact {
  cv::Mat response;  // CV_64F
  cv::Mat trace;     // CV_64F
};

Exact exact_harris(const cv::Mat& gray, int block_size) {
  const long double s2 = 1.0L / (4.0L * block_size * 255.0L) / (4.0L * block_size * 255.0L);
  cv::Mat dx16, dy16, dx, dy, a, b, c;
  cv::Sobel(gray, dx16, CV_16S, 1, 0, 3);
  cv::Sobel(gray, dy16, CV_16S, 0, 1, 3);
  dx16.convertTo(dx, CV_64F);
  dy16.convertTo(dy, CV_64F);
  const cv::Size window(block_size, block_size);
  cv::boxFilter(dx.mul(dx), a, CV_64F, window, cv::Point(-1, -1), false);
  cv::boxFilter(dx.mul(dy), b, CV_64F, window, cv::Point(-1, -1), false);
  cv::boxFilter(dy.mul(dy), c, CV_64F, window, cv::Point(-1, -1), false);
  Exact exact{cv::Mat(gray.size(), CV_64F), cv::Mat(gray.size(), CV_64F)};
  for (int y = 0; y < gray.rows; ++y) {
    for (int x = 0; x < gray.cols; ++x) {
      const long double sa = a.at<double>(y, x), sb = b.at<double>(y, x), sc = c.at<double>(y, x);
      exact.response.at<double>(y, x) = static_cast<double>(
          s2 * s2 * (sa * sc - sb * sb - static_cast<long double>(kK) * (sa + sc) * (sa + sc)));
      exact.trace.at<double>(y, x) = static_cast<double>(s2 * (sa + sc));
    }
  }
  return exact;
}

TEST(HarrisVsOpenCV, ResponseOnRealImages) {
  for (const RealImage& image : test::corner_test_images()) {
    for (const int block : {3, 5, 7}) {
      cv::Mat expected;
      cv::cornerHarris(image.gray, expected, block, 3, kK);
      double max_abs_cv = 0.0;
      cv::minMaxLoc(cv::abs(expected), nullptr, &max_abs_cv);
      const Exact exact = exact_harris(image.gray, block);
      for (const SimdPath path : available_simd_paths()) {
        HarrisDetector detector(
            {.width = image.gray.cols, .height = image.gray.rows, .block_size = block, .k = kK},
            path);
        const ImageView<const float> ours = detector.compute_response(test::view_of(image.gray));
        const std::string where = std::string(image.name) + " block " + std::to_string(block) +
                                  " " + std::string(to_string(path));
        double worst_exact = 0.0, worst_cv = 0.0, worst_cv_of_max = 0.0;
        int over = 0, flat = 0;
        for (int y = 0; y < ours.height(); ++y) {
          for (int x = 0; x < ours.width(); ++x) {
            const double r = ours(x, y);
            const double cv_r = expected.at<float>(y, x);
            const double exact_r = exact.response.at<double>(y, x);
            const double t = exact.trace.at<double>(y, x);
            if (t == 0.0) {
              // A flat window: R is exactly 0, and ours is; OpenCV's running sums may leave a
              // residue there (~1e-37), covered by the floor term.
              ASSERT_EQ(r, 0.0) << where << " (" << x << ", " << y << ")";
              ASSERT_LE(std::fabs(cv_r), 1e-5 * max_abs_cv) << where;
              ++flat;
              continue;
            }
            const double scale_exact = std::max(std::fabs(exact_r), kK * t * t);
            const double e_exact = std::fabs(r - exact_r) / scale_exact;
            ASSERT_LE(e_exact, 1e-5)
                << where << " (" << x << ", " << y << "): ours " << r << " exact " << exact_r;
            worst_exact = std::max(worst_exact, e_exact);

            const double scale = std::max(std::fabs(cv_r), kK * t * t);
            const double diff = std::fabs(r - cv_r);
            ASSERT_LE(diff, 1e-4 * scale + 1e-5 * max_abs_cv)
                << where << " (" << x << ", " << y << "): ours " << r << " cv " << cv_r;
            worst_cv = std::max(worst_cv, diff / scale);
            worst_cv_of_max = std::max(worst_cv_of_max, diff / max_abs_cv);
            if (diff > 1e-4 * scale) ++over;
          }
        }
        std::cout << "[ harris   ] " << where << ": vs exact " << worst_exact << "; vs OpenCV "
                  << worst_cv << " of max(|R|, k trace^2) (" << over << " pixels over 1e-4), "
                  << worst_cv_of_max << " of max|R|; " << flat << " flat pixels\n";
      }
    }
  }
}

constexpr std::size_t kTieAllowance = 2;

// Whether the corner at p could be in one set and not the other because of a near-tie in
// OpenCV's response `r`: its R is close to the threshold, to a 3x3 neighbour, to a corner of
// either list within min_distance or to the last corner of either list.
bool near_tie(cv::Point p, const cv::Mat& r, const cv::Mat& trace, double threshold, double max_abs,
              const std::vector<cv::Point>& competitors) {
  const double v = r.at<float>(p);
  const double t = trace.at<double>(p);
  const double tolerance = 1e-4 * std::max(std::fabs(v), kK * t * t) + 1e-5 * max_abs;
  const auto close_to = [&](double w) { return std::fabs(v - w) <= tolerance; };
  if (close_to(threshold)) return true;
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx)
      if ((dx != 0 || dy != 0) && close_to(r.at<float>(p + cv::Point(dx, dy)))) return true;
  for (const cv::Point& q : competitors) {
    if (q != p && close_to(r.at<float>(q))) return true;
  }
  return false;
}

TEST(HarrisVsOpenCV, SameCornersAsGoodFeaturesToTrack) {
  std::size_t ties = 0, compared = 0;
  for (const RealImage& image : test::corner_test_images()) {
    cv::Mat cv_response;
    cv::cornerHarris(image.gray, cv_response, 3, 3, kK);
    double max_r = 0.0, max_abs = 0.0;
    cv::minMaxLoc(cv_response, nullptr, &max_r);
    cv::minMaxLoc(cv::abs(cv_response), nullptr, &max_abs);
    const cv::Mat trace = exact_harris(image.gray, 3).trace;
    for (const int max_corners : {100, 1000, 100'000}) {
      std::vector<cv::Point2f> expected;
      cv::goodFeaturesToTrack(image.gray, expected, max_corners, 0.01, 10, cv::noArray(), 3, true,
                              kK);
      ASSERT_GT(expected.size(), 50u) << image.name << ": too few corners to prove anything";
      std::set<std::pair<int, int>> cv_set;
      for (const cv::Point2f& p : expected) {
        cv_set.insert({static_cast<int>(p.x), static_cast<int>(p.y)});
      }
      for (const SimdPath path : available_simd_paths()) {
        const std::string where = std::string(image.name) + " max " + std::to_string(max_corners) +
                                  " " + std::string(to_string(path));
        HarrisDetector detector({.width = image.gray.cols,
                                 .height = image.gray.rows,
                                 .block_size = 3,
                                 .k = kK,
                                 .quality_level = 0.01,
                                 .min_distance = 10,
                                 .max_corners = max_corners},
                                path);
        const auto corners = detector.detect(test::view_of(image.gray));
        std::set<std::pair<int, int>> our_set;
        for (const Corner& c : corners) our_set.insert({c.x, c.y});
        std::vector<std::pair<int, int>> only_ours, only_cv;
        std::set_difference(our_set.begin(), our_set.end(), cv_set.begin(), cv_set.end(),
                            std::back_inserter(only_ours));
        std::set_difference(cv_set.begin(), cv_set.end(), our_set.begin(), our_set.end(),
                            std::back_inserter(only_cv));
        bool same_order = corners.size() == expected.size();
        for (std::size_t i = 0; same_order && i < corners.size(); ++i) {
          same_order = corners[i].x == static_cast<int>(expected[i].x) &&
                       corners[i].y == static_cast<int>(expected[i].y);
        }
        std::cout << "[ harris   ] " << where << ": " << corners.size() << " corners, OpenCV "
                  << expected.size() << ", only ours " << only_ours.size() << ", only OpenCV "
                  << only_cv.size() << (same_order ? ", same order" : ", order differs") << "\n";

        // Competitors of a differing corner: the corners of both lists within min_distance,
        // and the last of each list.
        std::vector<cv::Point> all;
        for (const Corner& c : corners) all.emplace_back(c.x, c.y);
        for (const cv::Point2f& p : expected) all.emplace_back(cvRound(p.x), cvRound(p.y));
        std::vector<std::pair<int, int>> differing = only_ours;
        differing.insert(differing.end(), only_cv.begin(), only_cv.end());
        EXPECT_LE(differing.size(), kTieAllowance) << where;
        for (const auto& [x, y] : differing) {
          const cv::Point p(x, y);
          std::vector<cv::Point> competitors;
          for (const cv::Point& q : all) {
            if ((q - p).dot(q - p) < 100) competitors.push_back(q);
          }
          competitors.emplace_back(corners.back().x, corners.back().y);
          competitors.emplace_back(cvRound(expected.back().x), cvRound(expected.back().y));
          EXPECT_TRUE(near_tie(p, cv_response, trace, max_r * 0.01, max_abs, competitors))
              << where << ": corner (" << x << ", " << y << ") differs and is no near-tie";
        }
        ties += differing.size();
        compared += corners.size();
      }
    }
  }
  std::cout << "[ harris   ] " << compared << " corners compared, " << ties
            << " differing (near-ties)\n";
}

// Synthetic images full of exact ties (symmetric squares, a checkerboard): OpenCV breaks ties
// in favour of the later pixel, and so do we.
TEST(HarrisVsOpenCV, SameCornersOnSymmetricPatterns) {
  std::vector<std::pair<std::string, cv::Mat>> images;
  cv::Mat squares(120, 160, CV_8UC1, cv::Scalar(30));
  cv::rectangle(squares, cv::Rect(20, 12, 24, 24), cv::Scalar(200), cv::FILLED);
  cv::rectangle(squares, cv::Rect(90, 50, 40, 40), cv::Scalar(120), cv::FILLED);
  images.emplace_back("squares", squares);
  cv::Mat board(96, 128, CV_8UC1);
  for (int y = 0; y < board.rows; ++y)
    for (int x = 0; x < board.cols; ++x)
      board.at<std::uint8_t>(y, x) = ((x / 16 + y / 16) % 2) != 0 ? 220 : 20;
  images.emplace_back("checkerboard", board);
  for (const auto& [name, gray] : images) {
    for (const double min_distance : {0.0, 3.0, 10.0}) {
      std::vector<cv::Point2f> expected;
      cv::goodFeaturesToTrack(gray, expected, 1000, 0.01, min_distance, cv::noArray(), 3, true, kK);
      HarrisDetector detector({.width = gray.cols,
                               .height = gray.rows,
                               .min_distance = min_distance,
                               .max_corners = 1000});
      const auto corners = detector.detect(test::view_of(gray));
      ASSERT_GE(expected.size(), 8u) << name;
      ASSERT_EQ(corners.size(), expected.size()) << name << " min_distance " << min_distance;
      for (std::size_t i = 0; i < corners.size(); ++i) {
        EXPECT_EQ(cv::Point(corners[i].x, corners[i].y),
                  cv::Point(cvRound(expected[i].x), cvRound(expected[i].y)))
            << name << " min_distance " << min_distance << " #" << i;
      }
    }
  }
}

}  // namespace
}  // namespace epipole::vision
