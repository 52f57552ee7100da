// The NEON remap kernel against the scalar reference, bit for bit: odd widths, odd strides,
// unaligned rows, the minimum size, coordinates at and beyond every border; the reference
// against its definition; the float-to-fixed conversion; bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "epipole/core/error.hpp"
#include "epipole/core/fixed_point.hpp"
#include "epipole/vision/remap.hpp"
#include "random_image.hpp"
#include "remap_kernels.hpp"

namespace epipole::vision {
namespace {

// The definition, written out plainly: each neighbour is the pixel or the border value.
std::uint8_t expected_pixel(GrayView source, int x, int y, unsigned fraction, int border) {
  const auto at = [&](int px, int py) {
    return px >= 0 && py >= 0 && px < source.width() && py < source.height() ? source(px, py)
                                                                             : border;
  };
  const int fx = static_cast<int>(fraction & 31u);
  const int fy = static_cast<int>((fraction >> 5) & 31u);
  const int sum = at(x, y) * (32 - fx) * (32 - fy) + at(x + 1, y) * fx * (32 - fy) +
                  at(x, y + 1) * (32 - fx) * fy + at(x + 1, y + 1) * fx * fy;
  return static_cast<std::uint8_t>((sum + 512) >> 10);
}

// A map of width x height whose coordinates mix the interior, every border, just outside and
// far outside (down to int16 limits), with random fractions including values above 1023.
RemapMap mixed_map(int width, int height, int source_width, int source_height, std::uint32_t seed) {
  RemapMap map(width, height);
  std::mt19937 rng(seed);
  const auto pick = [&](int size) {
    const int edges[] = {-32768,   -32767,   -1000, -3,       -2,       -1,    0,    1,
                         size - 2, size - 1, size,  size + 1, size + 7, 32766, 32767};
    const int kind = static_cast<int>(rng() % 8);
    if (kind < 4) return std::uniform_int_distribution<int>(0, size - 1)(rng);
    if (kind < 6) return std::uniform_int_distribution<int>(-3, size + 2)(rng);
    return edges[rng() % std::size(edges)];
  };
  for (int v = 0; v < height; ++v) {
    std::int16_t* xy = map.xy().row(v);
    std::uint16_t* fractions = map.fractions().row(v);
    // Some rows lie wholly inside, so that the fast path runs on whole rows too.
    const bool inside_row = v % 3 == 0 && source_width >= 2 && source_height >= 2;
    for (int u = 0; u < width; ++u) {
      if (inside_row) {
        xy[2 * u] = static_cast<std::int16_t>(rng() % static_cast<unsigned>(source_width - 1));
        xy[2 * u + 1] = static_cast<std::int16_t>(rng() % static_cast<unsigned>(source_height - 1));
      } else {
        xy[2 * u] = static_cast<std::int16_t>(pick(source_width));
        xy[2 * u + 1] = static_cast<std::int16_t>(pick(source_height));
      }
      fractions[u] = static_cast<std::uint16_t>(rng() % 4 == 0 ? rng() : rng() % 1024);
    }
  }
  return map;
}

// A map that scales the destination onto the source with sub-pixel jitter: nearly every
// neighbourhood lies inside, so the SIMD kernels' fast paths run.
RemapMap smooth_map(int width, int height, int source_width, int source_height,
                    std::uint32_t seed) {
  std::mt19937 rng(seed);
  RemapMap map(width, height);
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      const int x = u * std::max(source_width - 1, 1) / std::max(width, 1);
      const int y = v * std::max(source_height - 1, 1) / std::max(height, 1);
      map.xy()(2 * u, v) = static_cast<std::int16_t>(x);
      map.xy()(2 * u + 1, v) = static_cast<std::int16_t>(y);
      map.fractions()(u, v) = static_cast<std::uint16_t>(rng() % 1024);
    }
  }
  return map;
}

struct Case {
  int source_width;
  int source_height;
  int extra_stride;
  std::size_t offset;
  int width;  // destination
  std::size_t destination_offset;
};

class RemapKernel : public ::testing::TestWithParam<Case> {};

TEST_P(RemapKernel, SimdRowsEqualReferenceAndDefinition) {
  const Case c = GetParam();
  for (const SimdPath path : available_simd_paths()) {
    if (path == SimdPath::reference) continue;
    kernels::RemapRowKernel* const kernel = kernels::remap_row_kernel(path);
    test::BufferImage image(c.source_width, c.source_height, c.source_width + c.extra_stride,
                            c.offset);
    const int height = 9;
    for (const test::Pattern pattern : {test::Pattern::noise, test::Pattern::saturated}) {
      test::fill(image.view(), pattern,
                 static_cast<std::uint32_t>(c.source_width * 131 + c.source_height));
      const GrayView source = image.cview();
      for (const bool smooth : {false, true}) {
        const auto seed = static_cast<std::uint32_t>(c.width + 17 * c.source_height);
        const RemapMap map =
            smooth ? smooth_map(c.width, height, c.source_width, c.source_height, seed)
                   : mixed_map(c.width, height, c.source_width, c.source_height, seed);
        for (const int border : {0, 1, 128, 255}) {
          const auto b = static_cast<std::uint8_t>(border);
          std::vector<std::uint8_t> ref(c.width + c.destination_offset + 8, 0x55);
          std::vector<std::uint8_t> simd(c.width + c.destination_offset + 8, 0xAA);
          for (int v = 0; v < height; ++v) {
            const std::int16_t* xy = map.xy().row(v);
            const std::uint16_t* fractions = map.fractions().row(v);
            kernels::remap_row_ref(source, xy, fractions, c.width, b,
                                   ref.data() + c.destination_offset);
            kernel(source, xy, fractions, c.width, b, simd.data() + c.destination_offset);
            for (int u = 0; u < c.width; ++u) {
              const std::uint8_t expected =
                  expected_pixel(source, xy[2 * u], xy[2 * u + 1], fractions[u], border);
              ASSERT_EQ(ref[c.destination_offset + u], expected)
                  << "row " << v << " column " << u << " border " << border;
              ASSERT_EQ(simd[c.destination_offset + u], expected)
                  << to_string(path) << " row " << v << " column " << u << " border " << border;
            }
            // Nothing written outside the row.
            for (std::size_t k = 0; k < c.destination_offset; ++k) ASSERT_EQ(simd[k], 0xAA);
            for (std::size_t k = c.destination_offset + c.width; k < simd.size(); ++k)
              ASSERT_EQ(simd[k], 0xAA);
          }
        }
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Shapes, RemapKernel,
                         ::testing::Values(Case{1, 1, 0, 0, 1, 0}, Case{1, 1, 3, 1, 17, 1},
                                           Case{2, 2, 0, 0, 8, 0}, Case{2, 3, 1, 1, 9, 3},
                                           Case{7, 5, 0, 3, 15, 1}, Case{8, 8, 5, 1, 16, 0},
                                           Case{21, 11, 3, 1, 23, 5}, Case{37, 9, 17, 7, 37, 2},
                                           Case{64, 16, 0, 0, 64, 0}, Case{129, 17, 1, 3, 131, 7},
                                           Case{640, 24, 0, 0, 641, 1},
                                           Case{641, 19, 63, 1, 639, 3}),
                         [](const ::testing::TestParamInfo<Case>& param_info) {
                           const Case& c = param_info.param;
                           return std::to_string(c.source_width) + "x" +
                                  std::to_string(c.source_height) + "_stride" +
                                  std::to_string(c.source_width + c.extra_stride) + "_offset" +
                                  std::to_string(c.offset) + "_to" + std::to_string(c.width) +
                                  "_offset" + std::to_string(c.destination_offset);
                         });

TEST(RemapKernel, EmptySourceGivesTheBorder) {
  const std::int16_t xy[2 * 9] = {0, 0, -1, -1, 5, 5, 0, 0, 1, 1, 0, 0, 0, 0, 0, 0, 0, 0};
  const std::uint16_t fractions[9] = {0, 1, 2, 3, 1023, 33, 0, 0, 0};
  const GrayView empty;
  for (const SimdPath path : available_simd_paths()) {
    kernels::RemapRowKernel* const kernel = kernels::remap_row_kernel(path);
    std::uint8_t out[9] = {};
    kernel(empty, xy, fractions, 9, 42, out);
    for (const std::uint8_t value : out) EXPECT_EQ(value, 42);
  }
}

TEST(Rectifier, IdentityMapReturnsTheImage) {
  for (const auto& [w, h] : {std::pair{1, 1}, std::pair{2, 2}, std::pair{13, 7}, std::pair{64, 48},
                             std::pair{333, 21}}) {
    test::BufferImage image(w, h, w + 3, 1);
    test::fill(image.view(), test::Pattern::noise, static_cast<std::uint32_t>(w * h));
    for (const SimdPath path : available_simd_paths()) {
      Rectifier rectifier(
          {.source_width = w, .source_height = h, .width = w, .height = h, .border = 77},
          RemapMap(w, h), path);
      const GrayView out = rectifier.rectify(image.cview());
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
          ASSERT_EQ(out(x, y), image.cview()(x, y)) << w << "x" << h << " at " << x << "," << y;
    }
  }
}

TEST(Rectifier, HalfPixelShiftAveragesAndBlendsTheBorder) {
  // Shifting by half a pixel right averages neighbours; the last column blends with the border.
  GrayImage image(16, 2);
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 16; ++x) image(x, y) = static_cast<std::uint8_t>(10 * x + y);
  RemapMap map(16, 2);
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 16; ++x) map.fractions()(x, y) = 16;  // fx = 16, fy = 0
  for (const SimdPath path : available_simd_paths()) {
    Rectifier rectifier(
        {.source_width = 16, .source_height = 2, .width = 16, .height = 2, .border = 200},
        map.clone(), path);
    const GrayView out = rectifier.rectify(image.view());
    for (int y = 0; y < 2; ++y) {
      for (int x = 0; x < 15; ++x) {
        // (a + b) / 2 rounded half up
        EXPECT_EQ(out(x, y), (image(x, y) + image(x + 1, y) + 1) / 2) << x << "," << y;
      }
      EXPECT_EQ(out(15, y), (image(15, y) + 200 + 1) / 2);
    }
  }
}

TEST(Rectifier, MatchesTheKernelsOnAMixedMap) {
  test::BufferImage image(100, 60, 107, 3);
  test::fill(image.view(), test::Pattern::blobs, 5);
  const RemapMap map = mixed_map(90, 70, 100, 60, 9);
  Rectifier ref({.source_width = 100, .source_height = 60, .width = 90, .height = 70, .border = 9},
                map.clone(), SimdPath::reference);
  Rectifier neon({.source_width = 100, .source_height = 60, .width = 90, .height = 70, .border = 9},
                 map.clone(), SimdPath::neon);
  const GrayView a = ref.rectify(image.cview());
  test::BufferImage into(90, 70, 95, 1);
  neon.rectify(image.cview(), into.view());
  for (int y = 0; y < 70; ++y)
    for (int x = 0; x < 90; ++x) {
      ASSERT_EQ(a(x, y), into.cview()(x, y)) << x << "," << y;
      ASSERT_EQ(a(x, y), expected_pixel(image.cview(), map.xy()(2 * x, y), map.xy()(2 * x + 1, y),
                                        map.fractions()(x, y), 9));
    }
}

// Row bands rectified on their own, in any order, make the whole image; rows outside are an
// error.
TEST(Rectifier, RowBandsMakeTheWholeImage) {
  test::BufferImage image(100, 60, 107, 3);
  test::fill(image.view(), test::Pattern::blobs, 6);
  const RemapMap map = mixed_map(90, 70, 100, 60, 9);
  const RectifierConfig config{
      .source_width = 100, .source_height = 60, .width = 90, .height = 70, .border = 9};
  Rectifier whole(config, map.clone());
  Rectifier banded(config, map.clone());
  const GrayView expected = whole.rectify(image.cview());
  GrayView out;
  for (const auto& [first, end] : {std::pair{47, 70}, std::pair{0, 23}, std::pair{23, 47}}) {
    out = banded.rectify_rows(image.cview(), first, end);
  }
  for (int y = 0; y < 70; ++y) {
    for (int x = 0; x < 90; ++x) ASSERT_EQ(out(x, y), expected(x, y)) << x << "," << y;
  }
  EXPECT_THROW(banded.rectify_rows(image.cview(), 60, 71), Error);
  EXPECT_THROW(banded.rectify_rows(image.cview(), 30, 20), Error);
  EXPECT_THROW(banded.rectify_rows(image.cview(), -1, 5), Error);
}

// A rectifier without an image of its own fills the caller's, in bands as well; it refuses to
// rectify into an image it does not have, and says so in its working set.
TEST(Rectifier, FillsTheCallersImageInBands) {
  test::BufferImage image(100, 60, 107, 3);
  test::fill(image.view(), test::Pattern::blobs, 7);
  const RemapMap map = mixed_map(90, 70, 100, 60, 9);
  RectifierConfig config{
      .source_width = 100, .source_height = 60, .width = 90, .height = 70, .border = 9};
  Rectifier whole(config, map.clone());
  config.own_output = false;
  Rectifier borrowing(config, map.clone(), SimdPath::neon);
  const GrayView expected = whole.rectify(image.cview());
  test::BufferImage into(90, 70, 93, 5);  // odd stride, unaligned rows
  for (const auto& [first, end] : {std::pair{31, 70}, std::pair{0, 31}}) {
    borrowing.rectify_rows(image.cview(), into.view(), first, end);
  }
  for (int y = 0; y < 70; ++y) {
    for (int x = 0; x < 90; ++x) ASSERT_EQ(into.cview()(x, y), expected(x, y)) << x << "," << y;
  }
  EXPECT_THROW(borrowing.rectify(image.cview()), Error);
  EXPECT_THROW(borrowing.rectify_rows(image.cview(), 0, 10), Error);
  EXPECT_THROW(borrowing.rectify_rows(image.cview(), into.view(), 69, 71), Error);
  test::BufferImage small(89, 70, 93, 0);
  EXPECT_THROW(borrowing.rectify_rows(image.cview(), small.view(), 0, 10), Error);
  EXPECT_EQ(borrowing.working_set_bytes(), whole.working_set_bytes() - 70u * 128);
}

TEST(Rectifier, StatesItsWorkingSet) {
  Rectifier rectifier({.source_width = 640, .source_height = 480, .width = 640, .height = 480},
                      RemapMap(640, 480));
  // height * (round_up(4w, 64) + round_up(2w, 64) + round_up(w, 64)), w = 640 is a multiple.
  EXPECT_EQ(rectifier.working_set_bytes(), 480u * (4 * 640 + 2 * 640 + 640));
  Rectifier odd({.source_width = 10, .source_height = 10, .width = 33, .height = 5},
                RemapMap(33, 5));
  EXPECT_EQ(odd.working_set_bytes(), 5u * (192 + 128 + 64));
}

TEST(RemapMap, FloatToFixedRoundsToNearestThirtySecond) {
  struct Expect {
    float value;
    int integer;
    int fraction;
  };
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  for (const Expect& e : std::vector<Expect>{
           {0.0f, 0, 0},
           {-0.0f, 0, 0},
           {1.0f / 64, 0, 0},  // 0.5 / 32: ties to even
           {3.0f / 64, 0, 2},  // 1.5 / 32
           {5.0f / 64, 0, 2},  // 2.5 / 32
           {-1.0f / 64, 0, 0},
           {-3.0f / 64, -1, 30},
           {2.5f, 2, 16},
           {-0.01f, 0, 0},
           {-0.02f, -1, 31},
           {0.99f, 1, 0},  // 31.68 -> 32
           {1023.984375f, 1024, 0},
           {32767.0f, 32767, 0},
           {40000.0f, 32767, 0},
           {-40000.0f, -32768, 0},
           {1e10f, 32767, 31},
           {inf, 32767, 31},
           {-inf, -32768, 0},
           {nan, -32768, 0},
       }) {
    std::int16_t integer = 123;
    const int fraction = to_fixed_point(e.value, &integer);
    EXPECT_EQ(integer, e.integer) << e.value;
    EXPECT_EQ(fraction, e.fraction) << e.value;
  }
}

TEST(RemapMap, FromFloatMapsBuildsBothPlanes) {
  Image<float> map_x(5, 3), map_y(5, 3);
  for (int v = 0; v < 3; ++v)
    for (int u = 0; u < 5; ++u) {
      map_x(u, v) = static_cast<float>(u) * 1.25f - 1.0f;
      map_y(u, v) = static_cast<float>(v) + 0.5f + static_cast<float>(u) / 32.0f;
    }
  const RemapMap map = RemapMap::from_float(map_x.view(), map_y.view());
  ASSERT_EQ(map.width(), 5);
  ASSERT_EQ(map.height(), 3);
  for (int v = 0; v < 3; ++v)
    for (int u = 0; u < 5; ++u) {
      std::int16_t x = 0, y = 0;
      const int fx = to_fixed_point(map_x(u, v), &x);
      const int fy = to_fixed_point(map_y(u, v), &y);
      EXPECT_EQ(map.xy()(2 * u, v), x);
      EXPECT_EQ(map.xy()(2 * u + 1, v), y);
      EXPECT_EQ(map.fractions()(u, v), fy * 32 + fx);
    }
  // u = 2, v = 1: x = 1.5 -> (1, 16); y = 1.5 + 2/32 -> (1, 18)
  EXPECT_EQ(map.xy()(4, 1), 1);
  EXPECT_EQ(map.xy()(5, 1), 1);
  EXPECT_EQ(map.fractions()(2, 1), 18 * 32 + 16);

  RemapMap into(5, 3);
  into.assign_float(map_x.view(), map_y.view());
  for (int v = 0; v < 3; ++v)
    for (int u = 0; u < 5; ++u) EXPECT_EQ(into.fractions()(u, v), map.fractions()(u, v));
  RemapMap wrong(4, 3);
  EXPECT_THROW(wrong.assign_float(map_x.view(), map_y.view()), Error);
  Image<float> small(4, 3);
  EXPECT_THROW(RemapMap::from_float(map_x.view(), small.view()), Error);
}

TEST(Rectifier, RejectsBadInput) {
  const auto config = [](int sw, int sh, int w, int h) {
    return RectifierConfig{.source_width = sw, .source_height = sh, .width = w, .height = h};
  };
  EXPECT_THROW(Rectifier(config(0, 10, 10, 10), RemapMap(10, 10)), Error);
  EXPECT_THROW(Rectifier(config(10, 40000, 10, 10), RemapMap(10, 10)), Error);
  EXPECT_THROW(Rectifier(config(10, 10, 0, 10), RemapMap(0, 10)), Error);
  EXPECT_THROW(Rectifier(config(10, 10, 10, 10), RemapMap(11, 10)), Error);
  EXPECT_THROW(Rectifier(config(10, 10, 10, 10), RemapMap(10, 9)), Error);
  EXPECT_THROW(Rectifier(config(10, 10, 10, 10), RemapMap()), Error);
  EXPECT_THROW(RemapMap(40000, 2), Error);
  EXPECT_THROW(RemapMap(-1, 2), Error);
  Image<std::int16_t> xy(10, 3);
  Image<std::uint16_t> fractions(6, 3);
  EXPECT_THROW(RemapMap(xy.view(), fractions.view()), Error);

  Rectifier rectifier(config(20, 10, 12, 8), RemapMap(12, 8));
  GrayImage wrong_source(20, 11), source(20, 10), wrong_output(12, 9), output(12, 8);
  EXPECT_THROW(rectifier.rectify(wrong_source.view()), Error);
  EXPECT_THROW(rectifier.rectify(source.view(), wrong_output.view()), Error);
  EXPECT_NO_THROW(rectifier.rectify(source.view(), output.view()));
  // The output may not overlap the source.
  EXPECT_THROW(rectifier.rectify(source.view(), source.view().sub(0, 0, 12, 8)), Error);
  EXPECT_THROW(rectifier.rectify(source.view(), source.view().sub(8, 2, 12, 8)), Error);
}

TEST(Rectifier, WildMapsGiveTheBorder) {
  // Every entry far outside: the whole output is the border, whatever the fraction.
  RemapMap map(37, 5);
  std::mt19937 rng(3);
  for (int v = 0; v < 5; ++v)
    for (int u = 0; u < 37; ++u) {
      const bool low = rng() % 2 == 0;
      map.xy()(2 * u, v) = static_cast<std::int16_t>(low ? -32768 + u : 32767 - u);
      map.xy()(2 * u + 1, v) = static_cast<std::int16_t>(rng() % 2 == 0 ? v : -20000);
      map.fractions()(u, v) = static_cast<std::uint16_t>(rng());
    }
  GrayImage image(30, 20);
  test::fill(image.view(), test::Pattern::noise, 1);
  for (const SimdPath path : available_simd_paths()) {
    Rectifier rectifier(
        {.source_width = 30, .source_height = 20, .width = 37, .height = 5, .border = 99},
        map.clone(), path);
    const GrayView out = rectifier.rectify(image.view());
    for (int v = 0; v < 5; ++v)
      for (int u = 0; u < 37; ++u) ASSERT_EQ(out(u, v), 99) << u << "," << v;
  }
}

}  // namespace
}  // namespace epipole::vision
