// Sparse stereo: the Hamming and box kernels of every path against the reference, bit for bit;
// matches on a synthetic pair shifted by a known (integer and half-pixel) disparity; bad input.
#include "epipole/vision/sparse_stereo.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "epipole/core/error.hpp"
#include "epipole/vision/fast.hpp"
#include "error_of.hpp"
#include "random_image.hpp"
#include "sparse_stereo_kernels.hpp"

namespace epipole::vision {
namespace {

using test::error_of;

TEST(SparseStereoKernels, HammingEqualsReference) {
  std::mt19937 rng(7);
  std::vector<std::uint8_t> data(32 * 20 + 7);
  for (auto& b : data) b = static_cast<std::uint8_t>(rng());
  data[5] = 0;  // some all-zero and all-one bytes
  data[40] = 0xFF;
  for (const std::size_t offset : {0u, 1u, 3u}) {
    const std::uint8_t* query = data.data() + 32 * 19 + offset;  // the last one, unaligned
    for (int n = 0; n <= 13; ++n) {
      std::vector<std::uint16_t> ref(static_cast<std::size_t>(n) + 1, 999);
      kernels::hamming_ref(query, data.data() + offset, n, ref.data());
      for (const SimdPath path : available_simd_paths()) {
        std::vector<std::uint16_t> out(static_cast<std::size_t>(n) + 1, 999);
        kernels::hamming_kernel(path)(query, data.data() + offset, n, out.data());
        ASSERT_EQ(out, ref) << to_string(path) << " n " << n << " offset " << offset;
      }
    }
  }
  std::vector<std::uint16_t> self(1);
  kernels::hamming_ref(data.data(), data.data(), 1, self.data());
  EXPECT_EQ(self[0], 0);
}

// The 5x5 box sums at every width from the smallest with a sum to past two vectors, and a
// camera's, over rows at odd strides and unaligned starts; entries without a sum keep their
// value; all-255 rows give the largest sum.
TEST(SparseStereoKernels, Box5EqualsReference) {
  std::mt19937 rng(5);
  for (int width = 1; width <= 48 || width == 641; width = width == 48 ? 641 : width + 1) {
    for (const int offset : {0, 1, 3}) {
      const int stride = width + 5;
      std::vector<std::uint8_t> image(static_cast<std::size_t>(5 * stride + offset));
      for (auto& b : image) b = static_cast<std::uint8_t>(rng());
      if (width % 7 == 0) std::fill(image.begin(), image.end(), std::uint8_t{255});
      const std::uint8_t* rows[5];
      for (int r = 0; r < 5; ++r) rows[r] = image.data() + offset + r * stride;
      std::vector<std::uint16_t> ref(static_cast<std::size_t>(width) + 1, 0xBEEF);
      kernels::box5_row_ref(rows, width, ref.data());
      EXPECT_EQ(ref[0], 0xBEEF);
      EXPECT_EQ(ref[static_cast<std::size_t>(width) - 1], 0xBEEF);
      if (width >= 5) {
        EXPECT_NE(ref[2], 0xBEEF);
        if (width % 7 == 0) {
          EXPECT_EQ(ref[static_cast<std::size_t>(width) - 3], 25 * 255);
        }
      }
      for (const SimdPath path : available_simd_paths()) {
        std::vector<std::uint16_t> out(static_cast<std::size_t>(width) + 1, 0xBEEF);
        kernels::box5_row_kernel(path)(rows, width, out.data());
        ASSERT_EQ(out, ref) << to_string(path) << " width " << width << " offset " << offset;
      }
    }
  }
}

// A textured scene: the left view and a right view whose pixel x shows the left's x + d
// (linear interpolation between pixels for half-pixel d).
struct ShiftedPair {
  // rows: the right view also lower by this many rows (a drifted rig).
  ShiftedPair(int width, int height, double d, int rows = 0)
      : left(width, height), right(width, height) {
    const int source_width = width + 40;
    GrayImage source(source_width, height);
    test::fill(source.view(), test::Pattern::blobs, 11);
    // Smooth it a little, so that a half-pixel shift is a meaningful interpolation.
    GrayImage smooth(source_width, height);
    for (int y = 0; y < height; ++y) {
      for (int x = 0; x < source_width; ++x) {
        const int a = source.view()(std::max(x - 1, 0), y);
        const int b = source.view()(std::min(x + 1, source_width - 1), y);
        smooth.view()(x, y) = static_cast<std::uint8_t>((a + 2 * source.view()(x, y) + b + 2) / 4);
      }
    }
    for (int y = 0; y < height; ++y) {
      for (int x = 0; x < width; ++x) {
        left.view()(x, y) = smooth.view()(x + 8, y);
        const double s = x + 8 + d;
        const int i = static_cast<int>(std::floor(s));
        const double f = s - i;
        const int from = std::clamp(y - rows, 0, height - 1);
        right.view()(x, y) = static_cast<std::uint8_t>(
            std::lround((1 - f) * smooth.view()(i, from) + f * smooth.view()(i + 1, from)));
      }
    }
  }
  GrayImage left, right;
};

std::vector<Corner> corners_of(GrayView image) {
  FastDetector fast({.width = image.width(), .height = image.height(), .threshold = 20});
  const auto c = fast.detect(image);
  return {c.begin(), c.end()};
}

TEST(SparseStereo, FindsAKnownDisparityOnEveryPath) {
  for (const double d : {7.0, 6.5}) {
    const ShiftedPair pair(160, 96, d);
    const auto left = corners_of(pair.left.view());
    const auto right = corners_of(pair.right.view());
    ASSERT_GT(left.size(), 40u);
    std::vector<SparseMatch> ref;
    for (const SimdPath path : available_simd_paths()) {
      SparseStereoMatcher matcher({.width = 160, .height = 96, .max_disparity = 32}, path);
      const auto m = matcher.match(pair.left.view(), left, pair.right.view(), right);
      ASSERT_GT(m.size(), 20u) << to_string(path);
      int close = 0;
      double error = 0;
      for (const SparseMatch& match : m) {
        EXPECT_FLOAT_EQ(match.xr, match.xl - match.disparity);
        EXPECT_LE(std::abs(match.yr - match.yl), 1.0f);
        EXPECT_LE(match.distance, 64);
        const double e = std::abs(static_cast<double>(match.disparity) - d);
        close += e <= 0.5 ? 1 : 0;
        error += e;
      }
      EXPECT_GE(close, static_cast<int>(m.size()) * 9 / 10) << to_string(path) << " d " << d;
      EXPECT_LT(error / static_cast<double>(m.size()), 0.25) << to_string(path) << " d " << d;
      if (path == SimdPath::reference) {
        ref.assign(m.begin(), m.end());
        continue;
      }
      ASSERT_EQ(m.size(), ref.size()) << to_string(path);
      for (std::size_t i = 0; i < ref.size(); ++i) {
        EXPECT_EQ(m[i].xl, ref[i].xl);
        EXPECT_EQ(m[i].disparity, ref[i].disparity);
        EXPECT_EQ(m[i].distance, ref[i].distance);
      }
    }
  }
}

TEST(SparseStereo, BoundsAndRangeAreRespected) {
  const ShiftedPair pair(160, 96, 12.0);
  const auto left = corners_of(pair.left.view());
  const auto right = corners_of(pair.right.view());
  // A range that excludes the true disparity finds (almost) nothing right.
  SparseStereoMatcher narrow({.width = 160, .height = 96, .max_disparity = 8});
  for (const SparseMatch& m : narrow.match(pair.left.view(), left, pair.right.view(), right)) {
    EXPECT_LT(m.disparity, 8 + 2.5f);  // the sub-pixel search may move it by 2
  }
  SparseStereoMatcher few({.width = 160, .height = 96, .max_disparity = 32, .max_matches = 5});
  EXPECT_EQ(few.match(pair.left.view(), left, pair.right.view(), right).size(), 5u);
  EXPECT_TRUE(few.truncated());
  SparseStereoMatcher some_corners(
      {.width = 160, .height = 96, .max_disparity = 32, .max_corners = 10});
  EXPECT_LE(some_corners.match(pair.left.view(), left, pair.right.view(), right).size(), 10u);
  EXPECT_TRUE(some_corners.truncated());
  // No corners, no matches.
  SparseStereoMatcher matcher({.width = 160, .height = 96});
  EXPECT_TRUE(matcher.match(pair.left.view(), {}, pair.right.view(), right).empty());
  EXPECT_FALSE(matcher.truncated());
}

// A rig drifted by 4 rows: along the rows (tolerance 1) the true partners are out of reach; the
// band of 6 rows finds them, 4 rows lower, and leaves match()'s matches as they were.
TEST(SparseStereo, TheBandFindsMatchesRowsApart) {
  const ShiftedPair pair(160, 96, 9.0, 4);
  const auto left = corners_of(pair.left.view());
  const auto right = corners_of(pair.right.view());
  for (const SimdPath path : available_simd_paths()) {
    SparseStereoMatcher matcher({.width = 160, .height = 96, .max_disparity = 32, .band_rows = 6},
                                path);
    const auto along = matcher.match(pair.left.view(), left, pair.right.view(), right);
    const std::vector<SparseMatch> before(along.begin(), along.end());
    int along_right = 0;
    for (const SparseMatch& m : along) along_right += std::abs(m.disparity - 9.0f) < 0.5f ? 1 : 0;
    const auto band = matcher.match_band(pair.left.view(), pair.right.view());
    ASSERT_GT(band.size(), 20u) << to_string(path);
    int four_rows = 0;
    for (const SparseMatch& m : band) {
      EXPECT_LE(std::abs(m.yr - m.yl), 6.0f);
      EXPECT_EQ(m.disparity, std::round(m.disparity)) << "whole pixels";
      four_rows += m.yr - m.yl == 4.0f && std::abs(m.disparity - 9.0f) < 1.0f ? 1 : 0;
    }
    EXPECT_GE(four_rows, static_cast<int>(band.size()) * 9 / 10) << to_string(path);
    EXPECT_LT(along_right, four_rows / 4) << to_string(path);
    ASSERT_EQ(before.size(), along.size());
    for (std::size_t i = 0; i < before.size(); ++i) {
      EXPECT_EQ(along[i].xl, before[i].xl);
      EXPECT_EQ(along[i].yl, before[i].yl);
      EXPECT_EQ(along[i].yr, before[i].yr);
      EXPECT_EQ(along[i].disparity, before[i].disparity);
      EXPECT_EQ(along[i].distance, before[i].distance);
    }
  }
  SparseStereoMatcher no_band({.width = 160, .height = 96});
  no_band.match(pair.left.view(), left, pair.right.view(), right);
  EXPECT_THROW(no_band.match_band(pair.left.view(), pair.right.view()), Error);
}

TEST(SparseStereo, BadInputIsAClearError) {
  EXPECT_NE(error_of([] {
              SparseStereoMatcher m({.width = 64, .height = 48, .max_disparity = 64});
            }).find("smaller than the image width"),
            std::string::npos);
  EXPECT_NE(error_of([] { SparseStereoMatcher m({.width = 20, .height = 48}); }).find("outside"),
            std::string::npos);
  EXPECT_NE(error_of([] {
              SparseStereoMatcher m({.width = 64, .height = 48, .max_disparity = 16, .ratio = 0});
            }).find("ratio 0"),
            std::string::npos);
  EXPECT_NE(error_of([] {
              SparseStereoMatcher m(
                  {.width = 64, .height = 48, .max_disparity = 16, .row_tolerance = 40});
            }).find("row tolerance 40"),
            std::string::npos);
  EXPECT_NE(
      error_of([] {
        SparseStereoMatcher m(
            {.width = 64, .height = 48, .max_disparity = 16, .row_tolerance = 2, .band_rows = 1});
      }).find("band rows 1 must be 0 or in 2..64"),
      std::string::npos);
  GrayImage a(64, 48), b(64, 47);
  test::fill(a.view(), test::Pattern::noise, 1);
  test::fill(b.view(), test::Pattern::noise, 2);
  SparseStereoMatcher matcher({.width = 64, .height = 48, .max_disparity = 16});
  EXPECT_NE(error_of([&] { matcher.match(a.view(), {}, b.view(), {}); }).find("differ in size"),
            std::string::npos);
  const std::vector<Corner> outside = {{70, 10, 1.0f}};
  EXPECT_NE(error_of([&] {
              matcher.match(a.view(), outside, a.view(), {});
            }).find("corner (70, 10) is outside the 64x48 image"),
            std::string::npos);
}

}  // namespace
}  // namespace epipole::vision
