// The ground-truth figures on hand-made maps whose every count is known.
#include "epipole/vision/disparity_quality.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "epipole/core/error.hpp"
#include "epipole/vision/stereo.hpp"
#include "error_of.hpp"

namespace epipole::vision {
namespace {

TEST(DisparityQuality, CountsEachErrorBandMissingPixelsAndUnknownTruth) {
  // One row of 10: truth 40 px everywhere but two unknown pixels (0 and NaN).
  Image<float> truth(10, 1);
  Image<std::int16_t> disparity(10, 1);
  const float known = 40.0f;
  const float errors[10] = {0, 0.5f, 1.5f, 2.5f, 3.5f, -4.5f, 0, 0, 0, 0};
  for (int x = 0; x < 10; ++x) {
    truth(x, 0) = known;
    disparity(x, 0) = static_cast<std::int16_t>(std::lround((known + errors[x]) * kDisparityScale));
  }
  truth(6, 0) = 0;                                        // unknown
  truth(7, 0) = std::numeric_limits<float>::quiet_NaN();  // unknown
  disparity(8, 0) = kInvalidDisparity;                    // missing
  disparity(9, 0) = -5;                                   // missing (any negative)
  const DisparityQuality q = disparity_quality(disparity.view(), truth.view());
  EXPECT_EQ(q.known, 8);
  EXPECT_EQ(q.valid, 6);
  EXPECT_DOUBLE_EQ(q.density, 6.0 / 8);
  EXPECT_DOUBLE_EQ(q.bad1, 6.0 / 8);  // 1.5, 2.5, 3.5, 4.5 and the two missing
  EXPECT_DOUBLE_EQ(q.bad2, 5.0 / 8);  // 2.5, 3.5, 4.5, missing x2
  EXPECT_DOUBLE_EQ(q.bad4, 3.0 / 8);  // 4.5, missing x2
  // D1: off by more than 3 px and 5 % of 40 (2 px): 3.5 and 4.5, and the missing.
  EXPECT_DOUBLE_EQ(q.d1, 4.0 / 8);
  EXPECT_DOUBLE_EQ(q.mean_error, (0 + 0.5 + 1.5 + 2.5 + 3.5 + 4.5) / 6);
}

TEST(DisparityQuality, D1NeedsBothThreeAndFivePercent) {
  // 4 px off at a truth of 100 px is 4 %: not a D1 error; at 60 px it is 6.7 %: one.
  Image<float> truth(2, 1);
  Image<std::int16_t> disparity(2, 1);
  truth(0, 0) = 100;
  truth(1, 0) = 60;
  disparity(0, 0) = 104 * kDisparityScale;
  disparity(1, 0) = 64 * kDisparityScale;
  EXPECT_DOUBLE_EQ(disparity_quality(disparity.view(), truth.view()).d1, 0.5);
}

TEST(DisparityQuality, TheMaskLimitsThePixelsCounted) {
  Image<float> truth(4, 1);
  Image<std::int16_t> disparity(4, 1);
  Image<std::uint8_t> mask(4, 1);
  for (int x = 0; x < 4; ++x) {
    truth(x, 0) = 10;
    disparity(x, 0) = x < 2 ? 10 * kDisparityScale : kInvalidDisparity;
    mask(x, 0) = x % 2 == 0 ? 255 : 0;
  }
  const DisparityQuality q = disparity_quality(disparity.view(), truth.view(), mask.view());
  EXPECT_EQ(q.known, 2);
  EXPECT_EQ(q.valid, 1);
  EXPECT_DOUBLE_EQ(q.bad2, 0.5);
}

TEST(DisparityQuality, NoTruthGivesZerosAndOtherSizesAreErrors) {
  Image<float> truth(3, 2);  // pixels start undefined: set here
  Image<std::int16_t> disparity(3, 2);
  for (int y = 0; y < 2; ++y) {
    for (int x = 0; x < 3; ++x) {
      truth(x, y) = 0;
      disparity(x, y) = 0;
    }
  }
  const DisparityQuality q = disparity_quality(disparity.view(), truth.view());
  EXPECT_EQ(q.known, 0);
  EXPECT_EQ(q.bad2, 0);
  Image<std::int16_t> other(2, 2);
  EXPECT_EQ(test::error_of([&] { disparity_quality(other.view(), truth.view()); }),
            "the disparity is 2x2 but the ground truth is 3x2");
  Image<std::uint8_t> mask(3, 1);
  EXPECT_EQ(test::error_of([&] { disparity_quality(disparity.view(), truth.view(), mask.view()); }),
            "the mask is 3x1 but the ground truth is 3x2");
}

}  // namespace
}  // namespace epipole::vision
