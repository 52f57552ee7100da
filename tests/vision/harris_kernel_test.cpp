// The NEON Harris response against the scalar reference, bit for bit (odd widths, odd strides,
// unaligned rows, the minimum sizes, block sizes 1..7); the reference against an independent
// exact computation; the detector's corner selection against a brute-force version of
// cv::goodFeaturesToTrack's rules; bad input.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "epipole/core/error.hpp"
#include "epipole/vision/harris.hpp"
#include "harris_kernels.hpp"
#include "random_image.hpp"

namespace epipole::vision {
namespace {

struct Case {
  int width;
  int height;
  int extra_stride;
  std::size_t offset;
};

// A float image in a plain buffer, with a chosen stride (in elements).
struct FloatBuffer {
  FloatBuffer(int w, int h, std::ptrdiff_t stride, float fill)
      : pixels(static_cast<std::size_t>(stride) * h + 1, fill), width(w), height(h), step(stride) {}
  ImageView<float> view() { return {pixels.data() + 1, width, height, step}; }  // unaligned
  std::vector<float> pixels;
  int width;
  int height;
  std::ptrdiff_t step;
};

int reflect101(int i, int n) {
  return i < 0 ? -i : i >= n ? 2 * n - 2 - i : i;
}

// The definition, computed naively and exactly: integer Sobel, integer window sums, then R in
// long double.
std::vector<long double> exact_response(GrayView image, int block_size, double k,
                                        std::vector<long double>* traces) {
  const int w = image.width(), h = image.height(), r = block_size / 2;
  std::vector<std::int64_t> xx(w * h), xy(w * h), yy(w * h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const auto p = [&](int dx, int dy) {
        return static_cast<int>(image(reflect101(x + dx, w), reflect101(y + dy, h)));
      };
      const int gx = p(1, -1) - p(-1, -1) + 2 * (p(1, 0) - p(-1, 0)) + p(1, 1) - p(-1, 1);
      const int gy = p(-1, 1) + 2 * p(0, 1) + p(1, 1) - p(-1, -1) - 2 * p(0, -1) - p(1, -1);
      xx[y * w + x] = gx * gx;
      xy[y * w + x] = gx * gy;
      yy[y * w + x] = gy * gy;
    }
  }
  const long double s = 1.0L / (4.0L * block_size * 255.0L);
  std::vector<long double> result(w * h);
  traces->assign(w * h, 0.0L);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      std::int64_t a = 0, b = 0, c = 0;
      for (int j = -r; j <= r; ++j) {
        for (int i = -r; i <= r; ++i) {
          const int at = reflect101(y + j, h) * w + reflect101(x + i, w);
          a += xx[at];
          b += xy[at];
          c += yy[at];
        }
      }
      const long double s4 = s * s * s * s;
      const auto trace = static_cast<long double>(a + c);
      result[y * w + x] = s4 * (static_cast<long double>(a * c - b * b) -
                                static_cast<long double>(k) * trace * trace);
      (*traces)[y * w + x] = s * s * trace;
    }
  }
  return result;
}

class HarrisKernel : public ::testing::TestWithParam<Case> {};

TEST_P(HarrisKernel, NeonEqualsReferenceBitForBit) {
  const Case c = GetParam();
  for (const int block : {1, 3, 5, 7}) {
    if (c.width < std::max(3, block) || c.height < std::max(3, block)) continue;
    for (const test::Pattern pattern :
         {test::Pattern::noise, test::Pattern::saturated, test::Pattern::blobs}) {
      test::BufferImage image(c.width, c.height, c.width + c.extra_stride, c.offset);
      test::fill(image.view(), pattern, static_cast<std::uint32_t>(c.width * 131 + c.height));
      std::vector<std::int32_t> ws_ref(kernels::harris_workspace_elements(c.width, block));
      std::vector<std::int32_t> ws_neon(ws_ref.size());
      FloatBuffer ref(c.width, c.height, c.width + c.extra_stride, -1.0f);
      FloatBuffer neon(c.width, c.height, c.width + c.extra_stride, -2.0f);
      for (const float k : {0.04f, 0.0f, 0.15f}) {
        kernels::harris_response_ref(image.cview(), block, k, ws_ref.data(), ref.view());
        kernels::harris_response_neon(image.cview(), block, k, ws_neon.data(), neon.view());
        for (int y = 0; y < c.height; ++y) {
          for (int x = 0; x < c.width; ++x) {
            ASSERT_EQ(std::bit_cast<std::uint32_t>(ref.view()(x, y)),
                      std::bit_cast<std::uint32_t>(neon.view()(x, y)))
                << "(" << x << ", " << y << ") block " << block << " k " << k << ": "
                << ref.view()(x, y) << " vs " << neon.view()(x, y);
          }
        }
      }
      // Nothing outside the view was written (the padding keeps its fill).
      for (int y = 0; y < c.height; ++y) {
        for (int x = c.width; x < c.width + c.extra_stride; ++x) {
          ASSERT_EQ(ref.view().row(y)[x], -1.0f);
          ASSERT_EQ(neon.view().row(y)[x], -2.0f);
        }
      }
    }
  }
}

TEST_P(HarrisKernel, ReferenceMatchesTheExactDefinition) {
  const Case c = GetParam();
  for (const int block : {3, 5, 7}) {
    if (c.width < block || c.height < block) continue;
    test::BufferImage image(c.width, c.height, c.width + c.extra_stride, c.offset);
    test::fill(image.view(), test::Pattern::blobs, static_cast<std::uint32_t>(c.width + block));
    std::vector<long double> traces;
    const std::vector<long double> exact = exact_response(image.cview(), block, 0.04, &traces);
    std::vector<std::int32_t> ws(kernels::harris_workspace_elements(c.width, block));
    FloatBuffer ours(c.width, c.height, c.width, 0.0f);
    kernels::harris_response_ref(image.cview(), block, 0.04f, ws.data(), ours.view());
    for (int y = 0; y < c.height; ++y) {
      for (int x = 0; x < c.width; ++x) {
        // Float rounding of a, b, c and of the last step: a few ulps of the largest term,
        // which is at most (a + c)^2 / 4.
        const long double e = exact[y * c.width + x];
        const long double t = traces[y * c.width + x];
        ASSERT_LE(std::fabs(static_cast<long double>(ours.view()(x, y)) - e), 1e-6L * t * t)
            << "(" << x << ", " << y << ") block " << block;
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Shapes, HarrisKernel,
                         ::testing::Values(Case{3, 3, 0, 0}, Case{3, 4, 1, 1}, Case{5, 5, 0, 3},
                                           Case{7, 7, 2, 1}, Case{8, 9, 1, 1}, Case{9, 8, 0, 2},
                                           Case{10, 7, 0, 0}, Case{17, 11, 3, 1},
                                           Case{23, 13, 17, 2}, Case{37, 9, 5, 7},
                                           Case{64, 16, 0, 0}, Case{77, 21, 13, 5},
                                           Case{129, 17, 1, 3}, Case{641, 19, 63, 1}),
                         [](const ::testing::TestParamInfo<Case>& param_info) {
                           const Case& c = param_info.param;
                           return std::to_string(c.width) + "x" + std::to_string(c.height) +
                                  "_stride" + std::to_string(c.width + c.extra_stride) + "_offset" +
                                  std::to_string(c.offset);
                         });

// The largest response: the NEON kernel's bits are the reference's, at odd widths and strides
// from unaligned rows, with NaNs (passed over), zeros of both signs (+0 when the largest) and
// nothing but NaNs (-inf).
TEST(HarrisMaxResponse, NeonEqualsReference) {
  std::uint32_t state = 777;
  const auto next = [&state] {
    state = state * 1664525u + 1013904223u;
    return state >> 8;
  };
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float values[] = {-5.0f, -1.0f, -0.0f, 0.0f, 2.0f, 9.5f, nan};
  for (const Case& c : {Case{1, 1, 0, 0}, Case{3, 2, 1, 1}, Case{4, 3, 0, 0}, Case{7, 5, 3, 1},
                        Case{17, 4, 2, 3}, Case{64, 9, 0, 0}, Case{101, 7, 5, 2}}) {
    for (int round = 0; round < 30; ++round) {
      FloatBuffer r(c.width, c.height, c.width + c.extra_stride, nan);
      for (int y = 0; y < c.height; ++y) {
        for (int x = 0; x < c.width; ++x) {
          // Round 0: NaNs only; odd rounds: no positive value, so zeros are the largest.
          const std::size_t pick = next() % (round % 2 == 1 ? 4 : std::size(values));
          r.view()(x, y) = round == 0 ? nan : values[pick];
        }
      }
      const float ref = kernels::harris_max_response_ref(r.view());
      const float neon = kernels::harris_max_response_neon(r.view());
      EXPECT_EQ(std::bit_cast<std::uint32_t>(neon), std::bit_cast<std::uint32_t>(ref))
          << c.width << "x" << c.height << ", round " << round << ": " << neon << " vs " << ref;
      if (round == 0) {
        EXPECT_EQ(ref, -std::numeric_limits<float>::infinity());
      }
    }
  }
}

// The candidate scan: the NEON kernel's candidates are the reference's, at every width around its
// blocks of eight, from unaligned rows, with values drawn from a few so that ties with the
// threshold and between neighbours are common, for thresholds negative, zero and positive.
TEST(HarrisCandidates, NeonEqualsReference) {
  std::uint32_t state = 12345;
  const auto next = [&state] {
    state = state * 1664525u + 1013904223u;
    return state >> 8;
  };
  const float values[] = {-2.0f, -0.0f, 0.0f, 0.5f, 1.0f, 1.0f, 2.0f, 3.0f, 7.5f};
  const float quiet_nan = std::numeric_limits<float>::quiet_NaN();
  std::size_t found = 0;
  for (const int width : {1, 2, 3, 8, 9, 10, 11, 16, 17, 18, 25, 33, 64, 101, 640}) {
    for (const float threshold : {-1.0f, 0.0f, 0.75f, 1.0f, 2.5f}) {
      for (int round = 0; round < 20; ++round) {
        std::vector<float> rows(3 * static_cast<std::size_t>(width) + 4);
        for (float& v : rows) v = values[next() % std::size(values)];
        if (round == 0 && width > 3) rows[1 + width + 2] = quiet_nan;  // never a candidate
        // Sparse rounds: most blocks of eight have nothing above the threshold.
        if (round % 2 == 1) {
          for (float& v : rows) v = next() % 16 == 0 ? v : -3.0f;
        }
        const float* above = rows.data() + 1;  // unaligned
        const float* row = above + width + 1;
        const float* below = row + width + 1;
        std::vector<std::uint32_t> ref(static_cast<std::size_t>(width) + 1, 77);
        std::vector<std::uint32_t> neon(ref.size(), 77);
        const std::size_t n_ref = kernels::harris_candidates_row_ref(above, row, below, width,
                                                                     threshold, 1000, ref.data());
        const std::size_t n_neon = kernels::harris_candidates_row_neon(
            above, row, below, width, threshold, 1000, neon.data());
        ASSERT_EQ(n_neon, n_ref) << "width " << width << ", threshold " << threshold;
        found += n_ref;
        EXPECT_EQ(neon, ref) << "width " << width << ", threshold " << threshold;
        for (std::size_t i = 0; i < n_ref; ++i) {
          const int x = static_cast<int>(ref[i] - 1000);
          ASSERT_TRUE(x >= 1 && x < width - 1);
          EXPECT_GT(row[x], threshold);
        }
      }
    }
  }
  EXPECT_GT(found, 1000u) << "the rows must hold candidates to compare";
}

// cv::goodFeaturesToTrack's selection, written the slow and obvious way from a response map.
std::vector<Corner> brute_force_corners(ImageView<const float> r, double quality,
                                        double min_distance, int max_corners) {
  float max_r = -std::numeric_limits<float>::infinity();
  for (int y = 0; y < r.height(); ++y)
    for (int x = 0; x < r.width(); ++x) max_r = std::max(max_r, r(x, y));
  const auto t = static_cast<float>(static_cast<double>(max_r) * quality);
  const auto kept = [&](int x, int y) { return r(x, y) > t ? r(x, y) : 0.0f; };
  std::vector<Corner> candidates;
  for (int y = 1; y < r.height() - 1; ++y) {
    for (int x = 1; x < r.width() - 1; ++x) {
      const float v = kept(x, y);
      if (v == 0.0f) continue;
      bool is_max = true;
      for (int j = -1; j <= 1; ++j)
        for (int i = -1; i <= 1; ++i) is_max = is_max && v >= kept(x + i, y + j);
      if (is_max) candidates.push_back({x, y, v});
    }
  }
  std::stable_sort(candidates.begin(), candidates.end(), [](const Corner& a, const Corner& b) {
    if (a.score != b.score) return a.score > b.score;
    return a.y != b.y ? a.y > b.y : a.x > b.x;  // ties: the later pixel first
  });
  std::vector<Corner> corners;
  for (const Corner& c : candidates) {
    if (static_cast<int>(corners.size()) == max_corners) break;
    bool close = false;
    for (const Corner& k : corners) {
      const double dx = c.x - k.x, dy = c.y - k.y;
      close = close || (min_distance >= 1.0 && dx * dx + dy * dy < min_distance * min_distance);
    }
    if (!close) corners.push_back(c);
  }
  return corners;
}

TEST(HarrisDetector, SelectsAsGoodFeaturesToTrack) {
  GrayImage image(203, 151);
  test::fill(image.view(), test::Pattern::blobs, 5);
  for (const double min_distance : {0.0, 0.5, 1.0, 2.5, 4.5, 10.0, 10.5, 33.3, 500.0}) {
    for (const int max_corners : {1, 7, 40, 100'000}) {
      for (const SimdPath path : available_simd_paths()) {
        HarrisDetector detector({.width = 203,
                                 .height = 151,
                                 .block_size = 3,
                                 .min_distance = min_distance,
                                 .max_corners = max_corners},
                                path);
        const auto corners = detector.detect(image.view());
        const std::vector<Corner> expected =
            brute_force_corners(detector.response(), 0.01, min_distance, max_corners);
        ASSERT_EQ(std::vector<Corner>(corners.begin(), corners.end()), expected)
            << "min_distance " << min_distance << " max_corners " << max_corners;
        ASSERT_GT(corners.size(), 0u);
      }
    }
  }
}

TEST(HarrisDetector, EveryPathAgreesOnEveryBlockSize) {
  GrayImage image(320, 240);
  test::fill(image.view(), test::Pattern::blobs, 9);
  for (const int block : {3, 5, 7, 9, 31}) {
    HarrisConfig config{.width = 320, .height = 240, .block_size = block, .max_corners = 500};
    HarrisDetector ref(config, SimdPath::reference);
    const auto a = ref.detect(image.view());
    ASSERT_GT(a.size(), 10u) << block;
    for (std::size_t i = 1; i < a.size(); ++i) ASSERT_GE(a[i - 1].score, a[i].score);
    for (const SimdPath path : available_simd_paths()) {
      HarrisDetector other(config, path);
      const auto b = other.detect(image.view());
      ASSERT_EQ(std::vector<Corner>(a.begin(), a.end()), std::vector<Corner>(b.begin(), b.end()))
          << block << " " << to_string(path);
      for (int y = 0; y < 240; ++y) {
        for (int x = 0; x < 320; ++x) {
          ASSERT_EQ(std::bit_cast<std::uint32_t>(ref.response()(x, y)),
                    std::bit_cast<std::uint32_t>(other.response()(x, y)))
              << "(" << x << ", " << y << ") block " << block << " " << to_string(path);
        }
      }
    }
  }
}

TEST(HarrisDetector, FindsTheFourCornersOfASquare) {
  GrayImage image(64, 48);
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 64; ++x) image(x, y) = (x >= 20 && x < 44 && y >= 12 && y < 36) ? 200 : 30;
  for (const SimdPath path : available_simd_paths()) {
    for (const int block : {3, 5, 7}) {
      HarrisDetector detector({.width = 64, .height = 48, .block_size = block}, path);
      auto corners = std::vector<Corner>(detector.detect(image.view()).begin(),
                                         detector.detect(image.view()).end());
      ASSERT_EQ(corners.size(), 4u) << to_string(path) << " block " << block;
      // The square's corner pixels are (20, 12), (43, 12), (20, 35), (43, 35); the peaks of R
      // sit within block / 2 of them (the wider window moves them), symmetrically.
      std::sort(corners.begin(), corners.end(), [](const Corner& a, const Corner& b) {
        return a.y != b.y ? a.y < b.y : a.x < b.x;
      });
      const int corner_x[4] = {20, 43, 20, 43}, corner_y[4] = {12, 12, 35, 35};
      for (int i = 0; i < 4; ++i) {
        EXPECT_LE(std::abs(corners[i].x - corner_x[i]), block / 2) << i << " block " << block;
        EXPECT_LE(std::abs(corners[i].y - corner_y[i]), block / 2) << i << " block " << block;
        EXPECT_GT(corners[i].score, 0.0f);
        EXPECT_EQ(corners[i].score, corners[0].score) << "the square is symmetric";
      }
      EXPECT_EQ(corners[0].x + corners[1].x, 63);
      EXPECT_EQ(corners[0].y + corners[2].y, 47);
      EXPECT_FALSE(detector.truncated());
    }
  }
}

TEST(HarrisDetector, FlatImageHasNoCorners) {
  GrayImage image(40, 30);
  for (int y = 0; y < 30; ++y)
    for (int x = 0; x < 40; ++x) image(x, y) = 77;
  HarrisDetector detector({.width = 40, .height = 30});
  EXPECT_TRUE(detector.detect(image.view()).empty());
  EXPECT_EQ(detector.max_response(), 0.0f);
  for (int y = 0; y < 30; ++y)
    for (int x = 0; x < 40; ++x) ASSERT_EQ(detector.response()(x, y), 0.0f);
}

TEST(HarrisDetector, KeepsTheStrongestWhenBounded) {
  GrayImage image(200, 150);
  test::fill(image.view(), test::Pattern::blobs, 3);
  HarrisDetector all({.width = 200, .height = 150, .max_corners = 100'000});
  const std::vector<Corner> every(all.detect(image.view()).begin(), all.detect(image.view()).end());
  ASSERT_GT(every.size(), 30u);
  EXPECT_FALSE(all.truncated());
  HarrisDetector some({.width = 200, .height = 150, .max_corners = 25});
  const auto kept = some.detect(image.view());
  ASSERT_EQ(kept.size(), 25u);
  EXPECT_TRUE(some.truncated());
  EXPECT_EQ(std::vector<Corner>(kept.begin(), kept.end()),
            std::vector<Corner>(every.begin(), every.begin() + 25));
}

TEST(HarrisDetector, MinimumSizes) {
  for (const int block : {1, 3, 5, 7}) {
    const int n = std::max(3, block);
    GrayImage image(n, n);
    test::fill(image.view(), test::Pattern::noise, 1);
    for (const SimdPath path : available_simd_paths()) {
      HarrisDetector detector({.width = n, .height = n, .block_size = block}, path);
      const auto corners = detector.detect(image.view());
      EXPECT_LE(corners.size(), static_cast<std::size_t>((n - 2) * (n - 2)));
      EXPECT_THROW(HarrisDetector({.width = n - 1, .height = n, .block_size = block}, path), Error);
      EXPECT_THROW(HarrisDetector({.width = n, .height = n - 1, .block_size = block}, path), Error);
    }
  }
}

TEST(HarrisDetector, RejectsBadInput) {
  const auto make = [](HarrisConfig config) { HarrisDetector detector(config); };
  const HarrisConfig good{.width = 32, .height = 32};
  EXPECT_NO_THROW(make(good));
  for (const int block : {0, 2, 4, -3, 33, kHarrisMaxBlockSize + 2}) {
    HarrisConfig c = good;
    c.block_size = block;
    EXPECT_THROW(make(c), Error) << block;
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  for (const double k : {-0.04, nan, inf, 1e-9, 2.0}) {
    HarrisConfig c = good;
    c.k = k;
    EXPECT_THROW(make(c), Error) << k;
  }
  for (const double quality : {0.0, -0.01, nan, inf}) {
    HarrisConfig c = good;
    c.quality_level = quality;
    EXPECT_THROW(make(c), Error) << quality;
  }
  for (const double distance : {-1.0, nan, inf}) {
    HarrisConfig c = good;
    c.min_distance = distance;
    EXPECT_THROW(make(c), Error) << distance;
  }
  HarrisConfig no_corners = good;
  no_corners.max_corners = 0;
  EXPECT_THROW(make(no_corners), Error);
  try {
    make({.width = 6, .height = 32, .block_size = 7});
    ADD_FAILURE() << "a 6x32 image with block size 7 was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("at least 7x7"), std::string::npos) << e.what();
  }
  HarrisDetector detector(good);
  GrayImage wrong(33, 32);
  EXPECT_THROW(detector.detect(wrong.view()), Error);
  EXPECT_THROW(detector.compute_response(wrong.view()), Error);
}

TEST(HarrisDetector, WorkingSetIsTheStatedFormula) {
  HarrisDetector detector(
      {.width = 641, .height = 480, .block_size = 5, .min_distance = 10, .max_corners = 300});
  const std::size_t w = 641, h = 480, b = 5, s = 656;  // 641 rounded up to a multiple of 16
  const std::size_t cells = ((w + 9) / 10) * ((h + 9) / 10);
  EXPECT_EQ(detector.working_set_bytes(),
            4 * s * h + 12 * (b * w + w + b - 1) + 4 * (w - 2) * (h - 2) + 4 * cells + 16 * 300);
}

}  // namespace
}  // namespace epipole::vision
