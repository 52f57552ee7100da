// The speckle filter: its row masks in NEON giving the reference's bits at odd widths and
// unaligned rows, and the filter on every path against a flood fill written here.
#include "epipole/vision/speckle_filter.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <random>
#include <vector>

#include "epipole/vision/stereo.hpp"
#include "error_of.hpp"
#include "speckle_filter_kernels.hpp"

namespace epipole::vision {
namespace {

using Row = std::vector<std::int16_t>;

// Disparities in smooth patches with noise, invalid pixels (two negative values) scattered.
Row random_map(std::size_t n, std::uint32_t seed) {
  std::mt19937 random(seed);
  Row out(n);
  int level = 400;
  for (auto& d : out) {
    const auto r = static_cast<unsigned>(random() % 100);
    if (r < 3) level = static_cast<int>(random() % 2000);
    if (r < 15) {
      d = r % 2 == 0 ? kInvalidDisparity : std::int16_t{-2};
    } else {
      d = static_cast<std::int16_t>(level + static_cast<int>(random() % 41) - 20);
    }
  }
  return out;
}

TEST(SpeckleMasks, ReferenceMarksValidLeftAndUp) {
  const Row row = {100, 110, 140, -16, 50, 50, 0};
  const Row above = {-16, 100, 125, 140, 30, 50, 16};
  std::uint64_t valid = 0, left = 0, up = 0;
  kernels::speckle_masks_row_ref(row.data(), above.data(), 7, 16, &valid, &left, &up);
  const auto pixels = [](std::uint64_t m) {
    std::vector<int> out;
    for (int x = 0; x < 16; ++x) {
      const std::uint64_t nibble = (m >> (4 * x)) & 0xF;
      EXPECT_TRUE(nibble == 0 || nibble == 0xF) << "all or nothing at " << x;
      if (nibble != 0) out.push_back(x);
    }
    return out;
  };
  EXPECT_EQ(pixels(valid), (std::vector<int>{0, 1, 2, 4, 5, 6}));
  EXPECT_EQ(pixels(left), (std::vector<int>{1, 5})) << "110 -> 140 is more than 16 apart";
  EXPECT_EQ(pixels(up), (std::vector<int>{1, 2, 5, 6}));
}

TEST(SpeckleMasks, NeonGivesTheReferencesBitsAtOddWidthsAndUnalignedRows) {
  for (int width = 1; width <= 70; ++width) {
    for (const int range : {0, 16, 32}) {
      for (const bool has_above : {false, true}) {
        const auto n = static_cast<std::size_t>(width) + 1;
        const Row row = random_map(n, static_cast<std::uint32_t>(width));
        const Row above = random_map(n, static_cast<std::uint32_t>(width + 1000));
        const std::size_t words = (static_cast<std::size_t>(width) + 15) / 16;
        std::vector<std::uint64_t> ref(3 * words, 7), neon(3 * words, 9);
        const std::int16_t* a = has_above ? above.data() + 1 : nullptr;  // unaligned
        kernels::speckle_masks_row_ref(row.data() + 1, a, width, range, ref.data(),
                                       ref.data() + words, ref.data() + 2 * words);
        kernels::speckle_masks_row_neon(row.data() + 1, a, width, range, neon.data(),
                                        neon.data() + words, neon.data() + 2 * words);
        EXPECT_EQ(neon, ref) << "width " << width << " range " << range << " above " << has_above;
      }
    }
  }
}

// The definition: a flood fill over 4-neighbours that are valid and close, each pixel of a
// region smaller than min_size made invalid.
void flood_filter(std::vector<std::int16_t>& d, int width, int height, int min_size, int range) {
  std::vector<int> region(d.size(), -1);
  std::vector<int> stack, members;
  for (int start = 0; start < width * height; ++start) {
    if (d[start] < 0 || region[start] >= 0) continue;
    stack = {start};
    members.clear();
    region[start] = start;
    while (!stack.empty()) {
      const int p = stack.back();
      stack.pop_back();
      members.push_back(p);
      const int x = p % width;
      const int y = p / width;
      const int next[4][2] = {{x - 1, y}, {x + 1, y}, {x, y - 1}, {x, y + 1}};
      for (const auto& [nx, ny] : next) {
        if (nx < 0 || ny < 0 || nx >= width || ny >= height) continue;
        const int q = ny * width + nx;
        if (d[q] < 0 || region[q] >= 0 || std::abs(d[q] - d[p]) > range) continue;
        region[q] = start;
        stack.push_back(q);
      }
    }
    if (static_cast<int>(members.size()) < min_size) {
      for (const int p : members) d[p] = kInvalidDisparity;
    }
  }
}

TEST(SpeckleFilter, EveryPathRemovesTheRegionsAFloodFillFinds) {
  for (const auto& [width, height] : {std::pair{1, 1}, std::pair{17, 9}, std::pair{64, 30},
                                      std::pair{75, 23}, std::pair{3, 40}}) {
    for (const int min_size : {2, 5, 30}) {
      for (const int range : {0, 1, 2}) {
        const auto n = static_cast<std::size_t>(width * height);
        Row expected = random_map(n, static_cast<std::uint32_t>(width * 100 + height));
        Row input = expected;
        flood_filter(expected, width, height, min_size, range * kDisparityScale);
        if (n > 100) {
          EXPECT_NE(expected, input) << "some region is small";
        }
        for (const SimdPath path : {SimdPath::reference, SimdPath::neon, best_simd_path()}) {
          Row out = input;
          SpeckleFilter filter(width, height, min_size, range);
          filter.apply(ImageView<std::int16_t>(out.data(), width, height, width), path);
          EXPECT_EQ(out, expected) << to_string(path) << " " << width << "x" << height
                                   << " min_size " << min_size << " range " << range;
          filter.apply(ImageView<std::int16_t>(out.data(), width, height, width), path);
          EXPECT_EQ(out, expected) << "a second pass changes nothing";
        }
      }
    }
  }
}

// Long runs (whole words of the masks, overlaps across words) in a row stride wider than the
// image: smooth patches of one disparity with a few holes and thin lines.
TEST(SpeckleFilter, LongRunsAndAStrideWiderThanTheImage) {
  constexpr int width = 75;
  constexpr int height = 20;
  constexpr int stride = 80;
  Row image(static_cast<std::size_t>(stride * height), 7);  // padding: never read as pixels
  Row expected(static_cast<std::size_t>(width * height));
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      std::int16_t d = x < 40 ? 320 : 800;           // two wide surfaces
      if (y == 5 && x > 10 && x < 60) d = 1600;      // a thin line across both: 49 px
      if (y > 12 && x == 20) d = kInvalidDisparity;  // a vertical hole
      if ((x * 7 + y * 3) % 23 == 0) d = kInvalidDisparity;
      image[static_cast<std::size_t>(y * stride + x)] = d;
      expected[static_cast<std::size_t>(y * width + x)] = d;
    }
  }
  for (const int min_size : {40, 60}) {
    Row want = expected;
    flood_filter(want, width, height, min_size, kDisparityScale);
    EXPECT_NE(want, expected) << "some region is small";
    for (const SimdPath path : {SimdPath::reference, SimdPath::neon, best_simd_path()}) {
      Row in = image;
      SpeckleFilter filter(width, height, min_size, 1);
      filter.apply(ImageView<std::int16_t>(in.data(), width, height, stride), path);
      Row out;
      for (int y = 0; y < height; ++y) {
        out.insert(out.end(), in.begin() + y * stride, in.begin() + y * stride + width);
        for (int x = width; x < stride; ++x) {
          EXPECT_EQ(in[static_cast<std::size_t>(y * stride + x)], 7) << "padding written";
        }
      }
      EXPECT_EQ(out, want) << to_string(path) << " min_size " << min_size;
    }
  }
  // Its memory: the union-find (one entry a pixel), the runs of two rows, three mask rows.
  EXPECT_EQ(SpeckleFilter(width, height, 40, 1).working_set_bytes(),
            (75u * 20 + 4 * 75) * sizeof(std::int32_t) + 3 * 5 * sizeof(std::uint64_t));
}

TEST(SpeckleFilter, ARingIsOneRegionAndOcclusionMarksStay) {
  // A ring of 10 pixels around a hole (176 is within 1 px of 160), and a lone pixel: with
  // min_size 10 the ring stays, the lone pixel goes.
  constexpr std::int16_t N = kInvalidDisparity;  // no disparity
  constexpr std::int16_t O = -2;                 // another negative value: kept as it is
  Row d = {160, 160, 160, 160, N, O,             //
           160, N,   N,   160, N, 320,           //
           160, 176, 160, 160, N, N};
  SpeckleFilter filter(6, 3, 10, 1);
  filter.apply(ImageView<std::int16_t>(d.data(), 6, 3, 6), SimdPath::neon);
  EXPECT_EQ(d, (Row{160, 160, 160, 160, N, O, 160, N, N, 160, N, N, 160, 176, 160, 160, N, N}));
}

TEST(SpeckleFilter, BadInputIsAClearError) {
  EXPECT_NE(test::error_of([] { SpeckleFilter f(0, 5, 10, 1); }).find("must not be empty"),
            std::string::npos);
  EXPECT_NE(test::error_of([] { SpeckleFilter f(5, 5, 0, 1); }).find("1 pixel or more"),
            std::string::npos);
  EXPECT_NE(test::error_of([] { SpeckleFilter f(5, 5, 4, 256); }).find("0..255"),
            std::string::npos);
  SpeckleFilter f(5, 5, 4, 1);
  Row d(24, 0);
  EXPECT_NE(test::error_of([&] {
              f.apply(ImageView<std::int16_t>(d.data(), 4, 6, 4), SimdPath::neon);
            }).find("made for 5x5"),
            std::string::npos);
}

}  // namespace
}  // namespace epipole::vision
