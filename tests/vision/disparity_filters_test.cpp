// The disparity post-filters: what the references do, and the NEON kernels giving the same bits
// at odd widths, odd strides and unaligned rows.
#include "epipole/vision/disparity_filters.hpp"

#include <gtest/gtest.h>

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

}  // namespace
}  // namespace epipole::vision
