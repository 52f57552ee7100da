// The stereo kernels of every SIMD path against the scalar reference, bit for bit: census at
// odd widths, strides and offsets; costs, aggregation, winner take all and box sums on random
// rows; and whole disparity images of both methods, with 1 and 2 threads.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

#include "epipole/core/error.hpp"
#include "epipole/vision/stereo.hpp"
#include "random_image.hpp"

namespace epipole::vision {
namespace {

using U16 = std::vector<std::uint16_t>;

U16 random_u16(std::size_t n, int max, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> dist(0, max);
  U16 v(n);
  for (auto& x : v) x = static_cast<std::uint16_t>(dist(rng));
  return v;
}

std::vector<SimdPath> simd_paths() {
  std::vector<SimdPath> paths;
  for (const SimdPath p : available_simd_paths()) {
    if (p != SimdPath::reference) paths.push_back(p);
  }
  return paths;
}

struct CensusCase {
  int width;
  int height;
  int extra_stride;
  std::size_t offset;
};

class StereoCensus : public ::testing::TestWithParam<CensusCase> {};

TEST_P(StereoCensus, SimdEqualsReference) {
  const CensusCase c = GetParam();
  const auto ref = kernels::stereo_kernels(SimdPath::reference);
  for (const test::Pattern pattern :
       {test::Pattern::noise, test::Pattern::saturated, test::Pattern::blobs}) {
    test::BufferImage image(c.width, c.height, c.width + c.extra_stride, c.offset);
    test::fill(image.view(), pattern, static_cast<std::uint32_t>(c.width * 7 + c.height));
    const GrayView view = image.cview();
    for (int y = 0; y < c.height; ++y) {
      const std::uint8_t* rows[7];
      for (int i = 0; i < 7; ++i) rows[i] = view.row(std::clamp(y - 3 + i, 0, c.height - 1));
      U16 ref_lo(c.width, 1), ref_hi(c.width, 1);
      ref.census(rows, c.width, ref_lo.data(), ref_hi.data());
      for (const SimdPath path : simd_paths()) {
        U16 lo(c.width, 2), hi(c.width, 2);
        kernels::stereo_kernels(path).census(rows, c.width, lo.data(), hi.data());
        ASSERT_EQ(lo, ref_lo) << to_string(path) << " row " << y;
        ASSERT_EQ(hi, ref_hi) << to_string(path) << " row " << y;
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Sizes, StereoCensus,
                         ::testing::Values(CensusCase{16, 8, 0, 0}, CensusCase{17, 9, 3, 1},
                                           CensusCase{40, 11, 5, 3}, CensusCase{77, 10, 1, 7},
                                           CensusCase{129, 12, 0, 5}));

TEST(StereoKernels, CostEqualsReference) {
  for (const int width : {17, 40, 65}) {
    for (const int D : {16, 32, 48}) {
      const auto n = static_cast<std::size_t>(width);
      const U16 llo = random_u16(n, 0xFFFF, 1), lhi = random_u16(n, 0x7FFF, 2);
      const U16 rlo = random_u16(n + D, 0xFFFF, 3), rhi = random_u16(n + D, 0x7FFF, 4);
      U16 ref(n * D, 0);
      kernels::cost_row_ref(llo.data(), lhi.data(), rlo.data(), rhi.data(), width, D, ref.data());
      for (const SimdPath path : simd_paths()) {
        U16 out(n * D, 1);
        kernels::stereo_kernels(path).cost(llo.data(), lhi.data(), rlo.data(), rhi.data(), width, D,
                                           out.data());
        ASSERT_EQ(out, ref) << to_string(path) << " width " << width << " D " << D;
      }
    }
  }
}

// Three rows of aggregation: path state carried from row to row must agree too.
TEST(StereoKernels, SgmEqualsReference) {
  for (const int width : {17, 33}) {
    for (const int D : {16, 48}) {
      const auto n = static_cast<std::size_t>(width);
      const std::size_t stride = static_cast<std::size_t>(D) + 16;
      struct State {
        U16 paths[2][3];
        U16 mins[2][3];
        U16 scratch;
        U16 sums;
      };
      const auto make_state = [&] {
        State s;
        for (auto& row : s.paths) {
          for (auto& p : row) {
            p.assign((n + 2) * stride, 0);
            for (std::size_t x = 0; x < n; ++x) {
              p[(x + 1) * stride + 7] = kernels::kSgmPad;
              p[(x + 1) * stride + 8 + static_cast<std::size_t>(D)] = kernels::kSgmPad;
            }
          }
        }
        for (auto& row : s.mins) {
          for (auto& m : row) m.assign(n + 2, 0);
        }
        s.scratch.assign(2 * stride, 0);
        s.sums.assign(n * D, 0);
        return s;
      };
      const auto run = [&](kernels::SgmRowKernel* kernel, State& s, const U16& cost, int p1, int p2,
                           int prev) {
        kernels::SgmRow row{};
        row.cost = cost.data();
        row.width = width;
        row.disparities = D;
        row.p1 = p1;
        row.p2 = p2;
        for (int k = 0; k < 3; ++k) {
          row.prev[k] = s.paths[prev][k].data();
          row.cur[k] = s.paths[1 - prev][k].data();
          row.prev_min[k] = s.mins[prev][k].data();
          row.cur_min[k] = s.mins[1 - prev][k].data();
        }
        row.scratch = s.scratch.data();
        row.sums = s.sums.data();
        kernel(row);
      };
      for (const SimdPath path : simd_paths()) {
        for (const auto& [p1, p2] : {std::pair{11, 120}, std::pair{1, 1}, std::pair{30, 400}}) {
          State ref = make_state();
          State simd = make_state();
          int prev = 0;
          for (int y = 0; y < 3; ++y) {
            const U16 cost = random_u16(n * D, 31, static_cast<std::uint32_t>(y + 10 * D));
            run(kernels::sgm_row_ref, ref, cost, p1, p2, prev);
            run(kernels::stereo_kernels(path).sgm, simd, cost, p1, p2, prev);
            prev = 1 - prev;
            ASSERT_EQ(simd.sums, ref.sums) << to_string(path) << " row " << y;
            for (int k = 0; k < 3; ++k) {
              ASSERT_EQ(simd.paths[prev][k], ref.paths[prev][k]) << to_string(path);
              ASSERT_EQ(simd.mins[prev][k], ref.mins[prev][k]) << to_string(path);
            }
          }
        }
      }
    }
  }
}

TEST(StereoKernels, WtaEqualsReference) {
  for (const int width : {17, 40}) {
    for (const int D : {16, 32}) {
      for (const int max : {3, 60, 2000}) {
        for (const int uniqueness : {0, 5, 15, 99}) {
          const auto n = static_cast<std::size_t>(width);
          const U16 sums = random_u16(n * D, max, static_cast<std::uint32_t>(max + D));
          U16 ref_sums = sums, ref_min(n + D, kernels::kNoCost), ref_disp(n + D, 0xFFFF);
          std::vector<std::int16_t> ref_out(n, 7), ref_best(n, 7);
          kernels::wta_row_ref(ref_sums.data(), width, D, uniqueness, ref_out.data(),
                               ref_best.data(), ref_min.data(), ref_disp.data());
          for (const SimdPath path : simd_paths()) {
            U16 s = sums, m(n + D, kernels::kNoCost), d(n + D, 0xFFFF);
            std::vector<std::int16_t> out(n, 9), best(n, 9);
            kernels::stereo_kernels(path).wta(s.data(), width, D, uniqueness, out.data(),
                                              best.data(), m.data(), d.data());
            const std::string where = cat(to_string(path), " width ", width, " D ", D, " max ", max,
                                          " uniqueness ", uniqueness);
            ASSERT_EQ(out, ref_out) << where;
            ASSERT_EQ(best, ref_best) << where;
            ASSERT_EQ(m, ref_min) << where;
            ASSERT_EQ(d, ref_disp) << where;
          }
        }
      }
    }
  }
}

TEST(StereoKernels, BoxEqualsReference) {
  for (const int width : {17, 40}) {
    for (const int D : {16, 32}) {
      const auto n = static_cast<std::size_t>(width) * D;
      const U16 base = random_u16(n, 1000, 5), add = random_u16(n, 31, 6),
                sub = random_u16(n, 31, 7);
      for (const SimdPath path : simd_paths()) {
        const auto k = kernels::stereo_kernels(path);
        for (const bool with_add : {false, true}) {
          for (const bool with_sub : {false, true}) {
            U16 ref = base, out = base;
            kernels::box_columns_ref(ref.data(), with_add ? add.data() : nullptr,
                                     with_sub ? sub.data() : nullptr, static_cast<int>(n) - 3);
            k.box_columns(out.data(), with_add ? add.data() : nullptr,
                          with_sub ? sub.data() : nullptr, static_cast<int>(n) - 3);
            ASSERT_EQ(out, ref) << to_string(path);
          }
        }
        for (const int radius : {1, 3, 10}) {
          U16 ref(n, 0), out(n, 1);
          kernels::box_row_ref(base.data(), width, D, radius, ref.data());
          k.box_row(base.data(), width, D, radius, out.data());
          ASSERT_EQ(out, ref) << to_string(path) << " radius " << radius;
        }
      }
    }
  }
}

std::vector<std::int16_t> disparities(const StereoConfig& config, SimdPath path, GrayView left,
                                      GrayView right) {
  StereoMatcher matcher(config, path);
  const auto d = matcher.compute(left, right);
  std::vector<std::int16_t> out;
  for (int y = 0; y < d.height(); ++y) out.insert(out.end(), d.row(y), d.row(y) + d.width());
  return out;
}

// A right view made from the left by shifting blobs: some structure to match.
TEST(StereoMatcher, PathsAndThreadsAgree) {
  const int width = 75;
  const int height = 23;
  test::BufferImage left(width, height, width + 3, 1);
  test::fill(left.view(), test::Pattern::blobs, 3);
  test::BufferImage right(width, height, width + 1, 2);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      right.view()(x, y) = left.cview()(std::min(width - 1, x + 5 + (y / 8)), y);
    }
  }
  for (const StereoMethod method : {StereoMethod::sgm, StereoMethod::bm}) {
    for (const int threads : {1, 2}) {
      StereoConfig config{.width = width, .height = height, .max_disparity = 16};
      config.method = method;
      config.threads = threads;
      config.speckle_size = 4;
      const auto ref = disparities(config, SimdPath::reference, left.cview(), right.cview());
      for (const SimdPath path : simd_paths()) {
        EXPECT_EQ(disparities(config, path, left.cview(), right.cview()), ref)
            << to_string(path) << " threads " << threads;
      }
      // The blobs' disparity (5..7 px) is found somewhere.
      const long found = std::count_if(ref.begin(), ref.end(), [](std::int16_t d) {
        return d >= 5 * kDisparityScale - 8 && d <= 7 * kDisparityScale + 8;
      });
      EXPECT_GT(found, static_cast<long>(ref.size()) / 3) << "threads " << threads;
      if (method == StereoMethod::bm && threads == 2) {
        config.threads = 1;
        EXPECT_EQ(disparities(config, SimdPath::reference, left.cview(), right.cview()), ref)
            << "block matching does not depend on the stripes";
      }
    }
  }
}

TEST(StereoMatcher, BadInputIsAClearError) {
  const auto message = [](const auto& make) -> std::string {
    try {
      make();
    } catch (const Error& e) {
      return e.what();
    }
    return "no error";
  };
  EXPECT_NE(message([] {
              StereoMatcher m({.width = 64, .height = 48, .max_disparity = 64});
            }).find("not smaller than the image width"),
            std::string::npos);
  EXPECT_NE(message([] {
              StereoMatcher m({.width = 640, .height = 48, .max_disparity = 40});
            }).find("multiple of 16"),
            std::string::npos);
  EXPECT_NE(message([] {
              StereoMatcher m({.width = 640, .height = 48, .max_disparity = 272});
            }).find("multiple of 16"),
            std::string::npos);
  GrayImage a(64, 32), b(64, 31);
  std::fill_n(a.view().row(0), a.stride() * 32, std::uint8_t{0});
  std::fill_n(b.view().row(0), b.stride() * 31, std::uint8_t{0});
  StereoMatcher matcher({.width = 64, .height = 32, .max_disparity = 16});
  EXPECT_NE(message([&] { matcher.compute(a.view(), b.view()); }).find("differ in size"),
            std::string::npos);
  EXPECT_NE(message([&] { matcher.compute(b.view(), b.view()); }).find("configured for 64x32"),
            std::string::npos);
}

}  // namespace
}  // namespace epipole::vision
