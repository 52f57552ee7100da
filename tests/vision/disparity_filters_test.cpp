// The disparity post-filters: what the references do, and the NEON kernels giving the same bits
// at odd widths, odd strides and unaligned rows.
#include "epipole/vision/disparity_filters.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

#include "disparity_filters_kernels.hpp"
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

TEST(SpatialFilter, SmoothsAlongARowBothWaysAndStopsAtEdgesAndHoles) {
  // A pixel's own weight 50 % (128/256), steps up to 2 px (32), one pass.
  std::vector<std::int16_t> row{160, 176, X, 320, 336, 800};
  SpatialFilter(6, 1, 50, 2, 1)
      .apply(ImageView<std::int16_t>(row.data(), 6, 1, 6), SimdPath::reference);
  // Left to right: 176 -> 160 + (16 * 128 + 128) >> 8 = 168; the hole stays and stops the
  // smoothing (320 is taken as it is); 336 -> 328; 800 is an edge. Right to left: 328 stays
  // beside the edge; 320 -> 328 + (-8 * 128 + 128) >> 8 = 324; 160 -> 168 - 4 = 164.
  EXPECT_EQ(row, (std::vector<std::int16_t>{164, 168, X, 324, 328, 800}));
  // Down a column, then up: the same values.
  std::vector<std::int16_t> column{160, 176, X, 320, 336, 800};
  SpatialFilter(1, 6, 50, 2, 1)
      .apply(ImageView<std::int16_t>(column.data(), 1, 6, 1), SimdPath::reference);
  EXPECT_EQ(column, row);
}

TEST(SpatialFilter, RowsFirstThenColumns) {
  // 2x2: along the rows nothing is close enough to blend (steps of 4 px); down the columns
  // 16 -> 0 + (16 * 128 + 128) >> 8 = 8 and back up 0 -> 8 - 4 = 4 (and so on).
  std::vector<std::int16_t> image{0, 64, 16, 80};
  SpatialFilter(2, 2, 50, 2, 1)
      .apply(ImageView<std::int16_t>(image.data(), 2, 2, 2), SimdPath::reference);
  EXPECT_EQ(image, (std::vector<std::int16_t>{4, 68, 8, 72}));
}

// Surfaces with a slope, noise, steps between them and holes: many blends, many edges.
std::vector<std::int16_t> surfaces(std::mt19937& rng, int width, int height, int stride) {
  std::vector<std::int16_t> image(static_cast<std::size_t>(stride) * height + 8, 77);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const int surface = (x / 5 + y / 4) % 3 * 400;
      const int noise = static_cast<int>(rng() % 41) - 20;
      image[static_cast<std::size_t>(y) * stride + x] =
          rng() % 9 == 0 ? X : static_cast<std::int16_t>(800 + surface + 3 * x + 2 * y + noise);
    }
  }
  return image;
}

TEST(SpatialFilter, NeonGivesTheReferencesBitsAtOddSizesStridesAndUnalignedRows) {
  std::mt19937 rng(13);
  for (int width : {1, 7, 8, 9, 17, 33, 100}) {
    for (int height : {1, 2, 7, 8, 9, 17, 23}) {
      for (int extra : {0, 3}) {
        for (int offset : {0, 1}) {
          for (int weight : {3, 128, 253}) {
            for (int step : {16, 112}) {
              const int stride = width + extra;
              std::vector<std::int16_t> ref = surfaces(rng, width, height + 1, stride);
              std::vector<std::int16_t> neon = ref;
              std::vector<std::int16_t> scratch(static_cast<std::size_t>(9 * width), 99);
              kernels::spatial_pass_ref(ref.data() + offset, stride, width, height, weight, step,
                                        nullptr);
              kernels::spatial_pass_neon(neon.data() + offset, stride, width, height, weight, step,
                                         scratch.data());
              ASSERT_EQ(neon, ref) << width << "x" << height << " stride " << stride << " offset "
                                   << offset << " weight " << weight << " step " << step;
            }
          }
        }
      }
    }
  }
}

TEST(SpatialFilter, EveryPathFiltersAnImageWithAnOddStrideAlikeAndLeavesThePadding) {
  std::mt19937 rng(17);
  const int width = 45, height = 19, stride = 51;
  const std::vector<std::int16_t> pixels = surfaces(rng, width, height, stride);
  std::vector<std::int16_t> results[3];
  const SimdPath paths[3] = {SimdPath::reference, SimdPath::neon, best_simd_path()};
  for (int i = 0; i < 3; ++i) {
    results[i] = pixels;
    SpatialFilter filter(width, height, 40, 3, 2);
    filter.apply(ImageView<std::int16_t>(results[i].data(), width, height, stride), paths[i]);
    EXPECT_EQ(filter.working_set_bytes(), 9u * width * sizeof(std::int16_t));
  }
  EXPECT_EQ(results[1], results[0]);
  EXPECT_EQ(results[2], results[0]);
  int changed = 0;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < stride; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * stride + x;
      if (x >= width) {
        EXPECT_EQ(results[0][i], pixels[i]) << "padding at " << x << "," << y;
      } else {
        EXPECT_EQ(results[0][i] < 0, pixels[i] < 0) << "nothing filled, nothing removed";
        changed += results[0][i] != pixels[i] ? 1 : 0;
      }
    }
  }
  EXPECT_GT(changed, width * height / 2) << "most valid pixels were smoothed";
}

TEST(SpatialFilter, BadSettingsAreErrors) {
  EXPECT_EQ(test::error_of([] { SpatialFilter(4, 4, 100, 2, 2); }),
            "spatial filter: a pixel's own weight is 100 %, expected 1..99");
  EXPECT_EQ(test::error_of([] { SpatialFilter(4, 4, 50, 0, 2); }),
            "spatial filter: the largest step is 0 px, expected 1..7");
  EXPECT_EQ(test::error_of([] { SpatialFilter(4, 4, 50, 2, 5); }),
            "spatial filter: 5 passes, expected 1..4");
  EXPECT_EQ(test::error_of([] { SpatialFilter(0, 4, 50, 2, 2); }),
            "spatial filter: empty size 0x4");
  SpatialFilter filter(4, 4, 50, 2, 2);
  std::vector<std::int16_t> other(9);
  EXPECT_EQ(test::error_of([&] {
              filter.apply(ImageView<std::int16_t>(other.data(), 3, 3, 3), SimdPath::reference);
            }),
            "spatial filter for 4x4 was given a 3x3 disparity");
}

}  // namespace
}  // namespace epipole::vision
