// Our image loader decodes the data sets to the same gray pixels as cv::imread(GRAYSCALE).
#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>

#include "epipole/core/image_io.hpp"
#include "test_data.hpp"

namespace epipole {
namespace {

class LoadLikeOpenCV : public ::testing::TestWithParam<const char*> {};

TEST_P(LoadLikeOpenCV, SamePixels) {
  const auto file = test::data_file(GetParam());
  const cv::Mat expected = cv::imread(file.string(), cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(expected.empty());
  const GrayImage ours = load_gray(file);
  ASSERT_EQ(ours.width(), expected.cols);
  ASSERT_EQ(ours.height(), expected.rows);
  int differing = 0;
  for (int y = 0; y < expected.rows; ++y) {
    for (int x = 0; x < expected.cols; ++x)
      differing += ours(x, y) != expected.at<std::uint8_t>(y, x);
  }
  EXPECT_EQ(differing, 0) << "of " << expected.total() << " pixels";
}

INSTANTIATE_TEST_SUITE_P(DataSets, LoadLikeOpenCV,
                         ::testing::Values("samples/left01.jpg", "samples/right14.jpg",
                                           "samples/aloeL.jpg", "samples/aloeGT.png",
                                           "samples/graf1.png", "samples/messi5.jpg"));

}  // namespace
}  // namespace epipole
