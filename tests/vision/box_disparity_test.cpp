// The median valid disparity of a box, against sorting, with invalid values, clipping and
// empty boxes.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

#include "epipole/core/error.hpp"
#include "epipole/vision/box_disparity.hpp"
#include "epipole/vision/stereo.hpp"

namespace epipole::vision {
namespace {

TEST(BoxDisparity, MedianOfTheValidValuesEqualsSorting) {
  constexpr int kMax = 64;
  std::mt19937 rng(2);
  Image<std::int16_t> disparity(97, 61);
  for (int y = 0; y < disparity.height(); ++y) {
    for (int x = 0; x < disparity.width(); ++x) {
      const int kind = static_cast<int>(rng() % 10);
      disparity(x, y) = static_cast<std::int16_t>(kind == 0   ? kInvalidDisparity
                                                  : kind == 1 ? 16 * kMax + 5
                                                              : rng() % (16 * kMax));
    }
  }
  BoxDisparity median(kMax);
  for (int i = 0; i < 300; ++i) {
    const int x = static_cast<int>(rng() % 120) - 10;
    const int y = static_cast<int>(rng() % 80) - 10;
    const int w = static_cast<int>(rng() % 40);
    const int h = static_cast<int>(rng() % 40);
    std::vector<int> valid;
    for (int v = std::max(y, 0); v < std::min(y + h, disparity.height()); ++v) {
      for (int u = std::max(x, 0); u < std::min(x + w, disparity.width()); ++u) {
        const int d = disparity(u, v);
        if (d >= 0 && d < 16 * kMax) valid.push_back(d);
      }
    }
    const auto m = median.median(disparity.view(), x, y, w, h);
    if (valid.empty()) {
      EXPECT_FALSE(m.has_value()) << x << "," << y << " " << w << "x" << h;
      continue;
    }
    std::sort(valid.begin(), valid.end());
    ASSERT_TRUE(m.has_value());
    EXPECT_EQ(*m, valid[(valid.size() - 1) / 2]) << x << "," << y << " " << w << "x" << h;
  }
}

TEST(BoxDisparity, SmallCasesAndBadRange) {
  Image<std::int16_t> d(4, 1);
  d(0, 0) = 32;
  d(1, 0) = 16;
  d(2, 0) = kInvalidDisparity;
  d(3, 0) = 48;
  BoxDisparity median(4);
  EXPECT_EQ(median.median(d.view(), 0, 0, 4, 1), std::optional<std::int16_t>(32));
  EXPECT_EQ(median.median(d.view(), 0, 0, 2, 1), std::optional<std::int16_t>(16)) << "lower";
  EXPECT_EQ(median.median(d.view(), 2, 0, 1, 1), std::nullopt);
  EXPECT_EQ(median.median(d.view(), 5, 0, 3, 3), std::nullopt);
  EXPECT_EQ(median.median(d.view(), 0, 0, 4, 1), std::optional<std::int16_t>(32)) << "again";
  EXPECT_THROW(BoxDisparity(0), Error);
  EXPECT_THROW(BoxDisparity(5000), Error);
}

}  // namespace
}  // namespace epipole::vision
