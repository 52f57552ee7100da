// The NEON FAST kernel against the scalar reference, bit for bit: odd widths, odd strides,
// unaligned rows, the minimum size, saturating intensities and every threshold class.
#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "epipole/core/error.hpp"
#include "epipole/vision/fast.hpp"
#include "fast_kernels.hpp"
#include "random_image.hpp"

namespace epipole::vision {
namespace {

struct Case {
  int width;
  int height;
  int extra_stride;
  std::size_t offset;
};

class FastKernel : public ::testing::TestWithParam<Case> {};

TEST_P(FastKernel, SimdRowsEqualReference) {
  const Case c = GetParam();
  for (const SimdPath path : available_simd_paths()) {
    if (path == SimdPath::reference) continue;
    kernels::FastRowKernel* const kernel = kernels::fast_row_kernel(path);
    for (const test::Pattern pattern :
         {test::Pattern::noise, test::Pattern::saturated, test::Pattern::blobs}) {
      test::BufferImage image(c.width, c.height, c.width + c.extra_stride, c.offset);
      test::fill(image.view(), pattern, static_cast<std::uint32_t>(c.width * 131 + c.height));
      const GrayView view = image.cview();
      for (const int threshold : {0, 1, 10, 20, 40, 100, 254, 255}) {
        std::vector<std::uint8_t> ref_scores(c.width, 0x55), simd_scores(c.width, 0xAA);
        std::vector<int> ref_columns(c.width), simd_columns(c.width);
        for (int y = 3; y < c.height - 3; ++y) {
          const std::string where = cat(to_string(path), " row ", y, " threshold ", threshold);
          const int n_ref = kernels::fast_row_ref(view.row(y), view.stride(), c.width, threshold,
                                                  ref_scores.data(), ref_columns.data());
          const int n_simd = kernel(view.row(y), view.stride(), c.width, threshold,
                                    simd_scores.data(), simd_columns.data());
          ASSERT_EQ(n_ref, n_simd) << where;
          ASSERT_EQ(ref_scores, simd_scores) << where;
          ASSERT_TRUE(
              std::equal(ref_columns.begin(), ref_columns.begin() + n_ref, simd_columns.begin()))
              << where;
        }
      }
    }
  }
}

TEST_P(FastKernel, DetectorsAgree) {
  const Case c = GetParam();
  test::BufferImage image(c.width, c.height, c.width + c.extra_stride, c.offset);
  test::fill(image.view(), test::Pattern::blobs, 7);
  for (const bool nonmax : {true, false}) {
    FastConfig config{.width = c.width,
                      .height = c.height,
                      .threshold = 15,
                      .nonmax = nonmax,
                      .max_corners = c.width * c.height};
    FastDetector ref(config, SimdPath::reference);
    const auto expected = ref.detect(image.cview());
    for (const SimdPath path : available_simd_paths()) {
      FastDetector detector(config, path);
      const auto corners = detector.detect(image.cview());
      ASSERT_EQ(std::vector<Corner>(expected.begin(), expected.end()),
                std::vector<Corner>(corners.begin(), corners.end()))
          << to_string(path);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Shapes, FastKernel,
                         ::testing::Values(Case{7, 7, 0, 0}, Case{8, 9, 1, 1}, Case{21, 11, 0, 3},
                                           Case{22, 12, 3, 1}, Case{23, 13, 17, 2},
                                           Case{35, 10, 0, 0}, Case{37, 9, 5, 7}, Case{38, 9, 0, 1},
                                           Case{39, 8, 2, 0}, Case{64, 16, 0, 0},
                                           Case{77, 21, 13, 5}, Case{129, 17, 1, 3},
                                           Case{640, 24, 0, 0}, Case{641, 19, 63, 1}),
                         [](const ::testing::TestParamInfo<Case>& param_info) {
                           const Case& c = param_info.param;
                           return std::to_string(c.width) + "x" + std::to_string(c.height) +
                                  "_stride" + std::to_string(c.width + c.extra_stride) + "_offset" +
                                  std::to_string(c.offset);
                         });

TEST(FastDetector, KeepsTheStrongestWhenBounded) {
  GrayImage image(200, 150);
  test::fill(image.view(), test::Pattern::blobs, 3);
  FastConfig all{
      .width = 200, .height = 150, .threshold = 10, .nonmax = true, .max_corners = 200 * 150};
  FastDetector unbounded(all, SimdPath::reference);
  std::vector<Corner> every(unbounded.detect(image.view()).begin(),
                            unbounded.detect(image.view()).end());
  ASSERT_GT(every.size(), 40u);
  ASSERT_FALSE(unbounded.truncated());

  FastConfig some = all;
  some.max_corners = 25;
  FastDetector bounded(some, best_simd_path());
  const auto kept = bounded.detect(image.view());
  ASSERT_EQ(kept.size(), 25u);
  EXPECT_TRUE(bounded.truncated());

  // The kept set is the 25 best by (score desc, raster order), returned in raster order.
  std::vector<Corner> expected = every;
  std::stable_sort(expected.begin(), expected.end(),
                   [](const Corner& a, const Corner& b) { return a.score > b.score; });
  expected.resize(25);
  std::sort(expected.begin(), expected.end(),
            [](const Corner& a, const Corner& b) { return a.y != b.y ? a.y < b.y : a.x < b.x; });
  EXPECT_EQ(std::vector<Corner>(kept.begin(), kept.end()), expected);
}

TEST(FastDetector, BucketsKeepTheStrongestPerCell) {
  GrayImage image(240, 180);
  test::fill(image.view(), test::Pattern::blobs, 9);
  FastConfig all{.width = 240, .height = 180, .threshold = 10, .max_corners = 240 * 180};
  FastDetector unbounded(all, SimdPath::reference);
  const auto every_span = unbounded.detect(image.view());
  const std::vector<Corner> every(every_span.begin(), every_span.end());

  FastConfig bucketed = all;
  bucketed.max_corners = 24;
  bucketed.grid_columns = 4;
  bucketed.grid_rows = 3;  // 12 cells of 60x60, 2 corners each
  FastDetector detector(bucketed);
  const auto kept_span = detector.detect(image.view());
  const std::vector<Corner> kept(kept_span.begin(), kept_span.end());
  EXPECT_TRUE(detector.truncated());
  EXPECT_TRUE(std::is_sorted(kept.begin(), kept.end(), [](const Corner& a, const Corner& b) {
    return a.y != b.y ? a.y < b.y : a.x < b.x;
  }));

  std::vector<Corner> expected;
  for (int cell_y = 0; cell_y < 3; ++cell_y) {
    for (int cell_x = 0; cell_x < 4; ++cell_x) {
      std::vector<Corner> in_cell;
      for (const Corner& c : every) {
        if (c.x / 60 == cell_x && c.y / 60 == cell_y) in_cell.push_back(c);
      }
      std::stable_sort(in_cell.begin(), in_cell.end(),
                       [](const Corner& a, const Corner& b) { return a.score > b.score; });
      in_cell.resize(std::min<std::size_t>(in_cell.size(), 2));
      expected.insert(expected.end(), in_cell.begin(), in_cell.end());
    }
  }
  ASSERT_GT(expected.size(), 12u);
  std::sort(expected.begin(), expected.end(),
            [](const Corner& a, const Corner& b) { return a.y != b.y ? a.y < b.y : a.x < b.x; });
  EXPECT_EQ(kept, expected);
}

TEST(FastDetector, RejectsImpossibleGrids) {
  EXPECT_THROW(
      FastDetector(
          {.width = 64, .height = 64, .max_corners = 5, .grid_columns = 3, .grid_rows = 2}),
      Error);  // fewer corners than cells
  EXPECT_THROW(FastDetector({.width = 64, .height = 64, .grid_columns = 0}), Error);
  EXPECT_THROW(FastDetector({.width = 64, .height = 64, .grid_rows = 65}), Error);
}

TEST(FastDetector, FindsIsolatedDots) {
  // A dot differs from its whole circle, so it is a corner whose score is the largest threshold
  // below the contrast: |200 - 20| - 1 = 179. Its neighbours see one odd pixel: no corner.
  GrayImage image(40, 30);
  for (int y = 0; y < 30; ++y)
    for (int x = 0; x < 40; ++x) image(x, y) = 20;
  image(8, 6) = 200;
  image(30, 20) = 200;
  for (const SimdPath path : available_simd_paths()) {
    FastDetector detector({.width = 40, .height = 30, .threshold = 50, .max_corners = 100}, path);
    const auto corners = detector.detect(image.view());
    ASSERT_EQ(corners.size(), 2u) << to_string(path);
    EXPECT_EQ(corners[0], (Corner{8, 6, 179.0f}));
    EXPECT_EQ(corners[1], (Corner{30, 20, 179.0f}));
  }
  // A dark dot on a bright background is found the same way.
  for (int y = 0; y < 30; ++y)
    for (int x = 0; x < 40; ++x) image(x, y) = static_cast<std::uint8_t>(220 - image(x, y));
  FastDetector detector({.width = 40, .height = 30, .threshold = 50, .max_corners = 100});
  const auto corners = detector.detect(image.view());
  ASSERT_EQ(corners.size(), 2u);
  EXPECT_EQ(corners[0], (Corner{8, 6, 179.0f}));
}

TEST(FastDetector, RejectsBadInput) {
  EXPECT_THROW(FastDetector({.width = 6, .height = 100}), Error);
  EXPECT_THROW(FastDetector({.width = 100, .height = 100, .max_corners = 0}), Error);
  FastDetector detector({.width = 32, .height = 32});
  GrayImage wrong(33, 32);
  EXPECT_THROW(detector.detect(wrong.view()), Error);
}

TEST(FastDetector, ClampsTheThresholdAsOpenCV) {
  FastDetector low({.width = 16, .height = 16, .threshold = -5});
  FastDetector high({.width = 16, .height = 16, .threshold = 300});
  EXPECT_EQ(low.config().threshold, 0);
  EXPECT_EQ(high.config().threshold, 255);
}

TEST(FastDetector, RunsNativeNeonOnArm) {
#if EPIPOLE_EXPECT_NATIVE_NEON
  EXPECT_EQ(best_simd_path(), SimdPath::neon);
  EXPECT_EQ(simd_description().rfind("neon (native", 0), 0u) << simd_description();
#else
  EXPECT_NE(simd_description().find("SIMDe"), std::string::npos) << simd_description();
#endif
}

}  // namespace
}  // namespace epipole::vision
