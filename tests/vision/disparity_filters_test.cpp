// The disparity post-filters: what the references do, and the NEON kernels giving the same bits
// at odd widths, odd strides and unaligned rows.
#include "epipole/vision/disparity_filters.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

#include "epipole/vision/stereo.hpp"
#include "error_of.hpp"

namespace epipole::vision {
namespace {

constexpr std::int16_t X = kInvalidDisparity;

std::vector<std::int16_t> filled(std::vector<std::int16_t> row, int max_hole) {
  kernels::fill_holes_row_ref(row.data(), static_cast<int>(row.size()), max_hole);
  return row;
}

TEST(FillHoles, AHoleTakesTheFartherOfItsTwoSides) {
  using Row = std::vector<std::int16_t>;
  EXPECT_EQ(filled({800, X, X, X, 320, 320}, 3), (Row{800, 320, 320, 320, 320, 320}));
  EXPECT_EQ(filled({160, X, 960}, 3), (Row{160, 160, 960}));
  EXPECT_EQ(filled({160, X, -1, X, 960}, 3), (Row{160, 160, 160, 160, 960}))
      << "any negative value is a hole";
}

TEST(FillHoles, LongHolesAndHolesAtTheBorderStay) {
  using Row = std::vector<std::int16_t>;
  EXPECT_EQ(filled({800, X, X, X, X, 320}, 3), (Row{800, X, X, X, X, 320}));
  EXPECT_EQ(filled({X, X, 320, X, 320, X}, 3), (Row{X, X, 320, 320, 320, X}));
  EXPECT_EQ(filled({800, X, 320}, 0), (Row{800, X, 320})) << "0: off";
  EXPECT_EQ(filled({X, X, X}, 5), (Row{X, X, X}));
}

TEST(FillHoles, NeonGivesTheReferencesBitsAtOddWidthsAndUnalignedRows) {
  std::mt19937 rng(7);
  for (int width : {1, 7, 8, 9, 15, 16, 17, 31, 33, 64, 100, 641}) {
    for (int offset : {0, 1, 3}) {
      for (int max_hole : {1, 3, 8, 17, 1000}) {
        // Valid stretches and holes of random lengths (some longer than eight, some not).
        std::vector<std::int16_t> ref(static_cast<std::size_t>(width + offset));
        for (int x = 0; x < width;) {
          const int run = 1 + static_cast<int>(rng() % (rng() % 2 ? 20 : 4));
          const bool hole = rng() % 2 == 0;
          for (int i = 0; i < run && x < width; ++i, ++x) {
            ref[static_cast<std::size_t>(offset + x)] =
                hole ? static_cast<std::int16_t>(-1 - static_cast<int>(rng() % 16))
                     : static_cast<std::int16_t>(rng() % 2048);
          }
        }
        std::vector<std::int16_t> neon = ref;
        kernels::fill_holes_row_ref(ref.data() + offset, width, max_hole);
        kernels::fill_holes_row_neon(neon.data() + offset, width, max_hole);
        ASSERT_EQ(neon, ref) << "width " << width << " offset " << offset << " max " << max_hole;
      }
    }
  }
}

TEST(FillHoles, EveryPathFillsAnImageWithAnOddStrideAlike) {
  std::mt19937 rng(11);
  const int width = 37, height = 5, stride = 41;
  std::vector<std::int16_t> pixels(static_cast<std::size_t>(stride * height));
  for (auto& p : pixels) p = rng() % 3 == 0 ? X : static_cast<std::int16_t>(rng() % 1024);
  std::vector<std::int16_t> results[3];
  const SimdPath paths[3] = {SimdPath::reference, SimdPath::neon, best_simd_path()};
  for (int i = 0; i < 3; ++i) {
    results[i] = pixels;
    fill_holes(ImageView<std::int16_t>(results[i].data(), width, height, stride), 4, paths[i]);
  }
  EXPECT_EQ(results[1], results[0]);
  EXPECT_EQ(results[2], results[0]);
  EXPECT_NE(results[0], pixels) << "some holes were filled";
  for (int y = 0; y < height; ++y) {  // the padding beyond the width is untouched
    for (int x = width; x < stride; ++x) {
      EXPECT_EQ(results[0][static_cast<std::size_t>(y * stride + x)],
                pixels[static_cast<std::size_t>(y * stride + x)]);
    }
  }
  EXPECT_EQ(test::error_of([&] {
              fill_holes(ImageView<std::int16_t>(pixels.data(), width, height, stride), -1,
                         SimdPath::reference);
            }),
            "hole filling: the longest hole must be 0 or more, not -1");
}

TEST(TemporalFilter, BlendsSmallStepsTakesLargeOnesAndNeverKeepsOldDepthWhereThereIsNone) {
  TemporalFilter filter(5, 1, 25, 2);  // the new pair weighs 64/256; steps up to 2 px (32)
  std::vector<std::int16_t> first{160, 320, X, 480, 640};
  filter.apply(ImageView<std::int16_t>(first.data(), 5, 1, 5), SimdPath::reference);
  EXPECT_EQ(first, (std::vector<std::int16_t>{160, 320, X, 480, 640})) << "nothing to blend yet";
  std::vector<std::int16_t> second{192, 400, 480, X, 608};
  filter.apply(ImageView<std::int16_t>(second.data(), 5, 1, 5), SimdPath::reference);
  // 160 -> 192 (2 px): 160 + (32 * 64 + 128) >> 8 = 168; 320 -> 400 (5 px): taken at once; a
  // pixel new here is taken; one gone stays gone; 640 -> 608: 640 + (-32 * 64 + 128) >> 8 = 632.
  EXPECT_EQ(second, (std::vector<std::int16_t>{168, 400, 480, X, 632}));
  std::vector<std::int16_t> third{168, 400, 480, 480, 632};
  filter.apply(ImageView<std::int16_t>(third.data(), 5, 1, 5), SimdPath::reference);
  EXPECT_EQ(third, (std::vector<std::int16_t>{168, 400, 480, 480, 632}))
      << "a pixel gone in the pair before comes back as it is now";
  filter.reset();
  std::vector<std::int16_t> after_reset{0, 0, 0, 0, 0};
  filter.apply(ImageView<std::int16_t>(after_reset.data(), 5, 1, 5), SimdPath::reference);
  EXPECT_EQ(after_reset, (std::vector<std::int16_t>{0, 0, 0, 0, 0}));
}

TEST(TemporalFilter, NeonGivesTheReferencesBitsAtOddWidthsAndUnalignedRows) {
  std::mt19937 rng(5);
  for (int width : {1, 7, 8, 9, 16, 17, 33, 641}) {
    for (int offset : {0, 1, 3}) {
      for (int weight : {3, 64, 128, 253}) {
        for (int step : {16, 112}) {
          std::vector<std::int16_t> now(static_cast<std::size_t>(width + offset));
          std::vector<std::int16_t> last(now.size());
          for (std::size_t i = 0; i < now.size(); ++i) {
            last[i] = rng() % 5 == 0 ? X : static_cast<std::int16_t>(rng() % 4096);
            const int move = static_cast<int>(rng() % 2 ? rng() % 241 : rng() % 4096) - 120;
            now[i] =
                rng() % 7 == 0 ? X : static_cast<std::int16_t>(std::clamp(last[i] + move, 0, 4095));
          }
          std::vector<std::int16_t> now_neon = now, last_neon = last;
          kernels::temporal_row_ref(now.data() + offset, last.data() + offset, width, weight, step);
          kernels::temporal_row_neon(now_neon.data() + offset, last_neon.data() + offset, width,
                                     weight, step);
          ASSERT_EQ(now_neon, now) << width << " " << offset << " " << weight << " " << step;
          ASSERT_EQ(last_neon, last) << width << " " << offset << " " << weight << " " << step;
        }
      }
    }
  }
}

TEST(TemporalFilter, BadSettingsAreErrors) {
  EXPECT_EQ(test::error_of([] { TemporalFilter(4, 4, 0, 2); }),
            "temporal filter: the new pair's weight is 0 %, expected 1..99");
  EXPECT_EQ(test::error_of([] { TemporalFilter(4, 4, 50, 8); }),
            "temporal filter: the largest step is 8 px, expected 1..7");
  TemporalFilter filter(4, 4, 50, 2);
  std::vector<std::int16_t> other(9);
  EXPECT_EQ(test::error_of([&] {
              filter.apply(ImageView<std::int16_t>(other.data(), 3, 3, 3), SimdPath::reference);
            }),
            "temporal filter for 4x4 was given a 3x3 disparity");
}

}  // namespace
}  // namespace epipole::vision
