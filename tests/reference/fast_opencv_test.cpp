// FAST against cv::FAST on the real images of the data sets: the same corners, the same scores.
#include <gtest/gtest.h>

#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>

#include "epipole/vision/fast.hpp"
#include "opencv_view.hpp"
#include "real_images.hpp"
#include "test_data.hpp"

namespace epipole::vision {
namespace {

using test::RealImage;

TEST(FastVsOpenCV, SameCornersAndScoresOnRealImages) {
  for (const RealImage& image : test::corner_test_images()) {
    for (const int threshold : {10, 20, 40}) {
      std::vector<cv::KeyPoint> expected;
      cv::FAST(image.gray, expected, threshold, true);
      ASSERT_GT(expected.size(), 50u) << image.name << ": too few corners to prove anything";
      for (const SimdPath path : available_simd_paths()) {
        FastDetector detector({.width = image.gray.cols,
                               .height = image.gray.rows,
                               .threshold = threshold,
                               .nonmax = true,
                               .max_corners = image.gray.cols * image.gray.rows},
                              path);
        const auto corners = detector.detect(test::view_of(image.gray));
        const std::string where = std::string(image.name) + " threshold " +
                                  std::to_string(threshold) + " " + std::string(to_string(path));
        ASSERT_EQ(corners.size(), expected.size()) << where;
        for (std::size_t i = 0; i < corners.size(); ++i) {
          ASSERT_EQ(static_cast<float>(corners[i].x), expected[i].pt.x) << where << " #" << i;
          ASSERT_EQ(static_cast<float>(corners[i].y), expected[i].pt.y) << where << " #" << i;
          ASSERT_EQ(corners[i].score, expected[i].response) << where << " #" << i;
        }
      }
    }
  }
}

TEST(FastVsOpenCV, SameCornersWithoutSuppression) {
  const cv::Mat gray = cv::imread(test::data_file("samples/left01.jpg"), cv::IMREAD_GRAYSCALE);
  std::vector<cv::KeyPoint> expected;
  cv::FAST(gray, expected, 20, false);
  FastDetector detector({.width = gray.cols,
                         .height = gray.rows,
                         .threshold = 20,
                         .nonmax = false,
                         .max_corners = gray.cols * gray.rows});
  const auto corners = detector.detect(test::view_of(gray));
  ASSERT_EQ(corners.size(), expected.size());
  for (std::size_t i = 0; i < corners.size(); ++i) {
    ASSERT_EQ(static_cast<float>(corners[i].x), expected[i].pt.x) << i;
    ASSERT_EQ(static_cast<float>(corners[i].y), expected[i].pt.y) << i;
  }
}

}  // namespace
}  // namespace epipole::vision
