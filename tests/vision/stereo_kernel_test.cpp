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
#include "stereo_census.hpp"
#include "stereo_kernels.hpp"

namespace epipole::vision {
namespace {

using U16 = std::vector<std::uint16_t>;

template <typename T>
std::vector<T> random_values(std::size_t n, int max, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> dist(0, max);
  std::vector<T> v(n);
  for (auto& x : v) x = static_cast<T>(dist(rng));
  return v;
}
const auto random_u16 = random_values<std::uint16_t>;
const auto random_u8 = random_values<std::uint8_t>;

std::vector<SimdPath> simd_paths() {
  std::vector<SimdPath> paths;
  for (const SimdPath p : available_simd_paths()) {
    if (p != SimdPath::reference) paths.push_back(p);
  }
  return paths;
}

using U8 = std::vector<std::uint8_t>;
using I16 = std::vector<std::int16_t>;

// A census row of n pixels (4n bytes) in `planes` layout, laid out as `layout` from byte
// `offset` of the result.
U8 in_layout(const U8& planes, int n, kernels::CensusLayout layout, std::size_t offset) {
  U8 out(offset + planes.size(), 0);
  for (int x = 0; x < n; ++x) {
    kernels::set_census(layout, out.data() + offset, n, x,
                        kernels::census_at(kernels::CensusLayout::planes, planes.data(), n, x));
  }
  return out;
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
  const auto n = static_cast<std::size_t>(c.width);
  for (const test::Pattern pattern :
       {test::Pattern::noise, test::Pattern::saturated, test::Pattern::blobs}) {
    test::BufferImage image(c.width, c.height, c.width + c.extra_stride, c.offset);
    test::fill(image.view(), pattern, static_cast<std::uint32_t>(c.width * 7 + c.height));
    const GrayView view = image.cview();
    for (int y = 0; y < c.height; ++y) {
      const std::uint8_t* rows[7];
      for (int i = 0; i < 7; ++i) rows[i] = view.row(std::clamp(y - 3 + i, 0, c.height - 1));
      ASSERT_EQ(ref.census_layout, kernels::CensusLayout::planes);
      for (const int bits : {kernels::kCensusBits, kernels::kSparseCensusBits}) {
        U8 expected(4 * n, 1);
        ref.census(rows, c.width, bits, expected.data());
        for (int x = 0; x < c.width; ++x) {
          ASSERT_EQ(
              kernels::census_at(kernels::CensusLayout::planes, expected.data(), c.width, x) >>
                  bits,
              0u)
              << "bits past the census's are 0";
        }
        for (const SimdPath path : simd_paths()) {
          const auto simd = kernels::stereo_kernels(path);
          U8 out(4 * n, 2);
          simd.census(rows, c.width, bits, out.data());
          ASSERT_EQ(out, in_layout(expected, c.width, simd.census_layout, 0))
              << to_string(path) << " row " << y << " bits " << bits;
        }
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Sizes, StereoCensus,
                         ::testing::Values(CensusCase{16, 8, 0, 0}, CensusCase{17, 9, 3, 1},
                                           CensusCase{24, 8, 0, 0}, CensusCase{25, 9, 2, 1},
                                           CensusCase{31, 8, 1, 3}, CensusCase{40, 11, 5, 3},
                                           CensusCase{77, 10, 1, 7}, CensusCase{129, 12, 0, 5}));

// The right row's census reversed in either layout, odd and even lengths, its padding untouched.
TEST(StereoKernels, ReverseCensusReversesEachLayout) {
  for (const kernels::CensusLayout layout :
       {kernels::CensusLayout::planes, kernels::CensusLayout::words}) {
    for (const int n : {1, 2, 7, 16, 17, 40}) {
      const int padded = n + 5;
      const U8 census =
          random_u8(4 * static_cast<std::size_t>(n), 255, static_cast<std::uint32_t>(n));
      U8 reversed(4 * static_cast<std::size_t>(padded), 0xAB);
      kernels::reverse_census(layout, census.data(), n, padded, reversed.data());
      for (int k = 0; k < padded; ++k) {
        const std::uint32_t expected =
            k < n ? kernels::census_at(layout, census.data(), n, n - 1 - k) : 0xABABABABu;
        ASSERT_EQ(kernels::census_at(layout, reversed.data(), padded, k), expected)
            << (layout == kernels::CensusLayout::words ? "words" : "planes") << " n " << n
            << " pixel " << k;
      }
    }
  }
}

// Census rows at odd offsets inside larger buffers, so loads are unaligned, in each path's
// layout. 64, 128 and 256 have kernels of their own, for the pixels whose range lies inside the
// image.
TEST(StereoKernels, CostEqualsReference) {
  for (const int width : {17, 40, 65, 300}) {
    for (const int D : {16, 32, 48, 64, 128, 256}) {
      const auto n = static_cast<std::size_t>(width);
      // Random censuses, in planes. Bits 16..30 too: a kernel that counts them in the sparse
      // census's cost fails. (No census has bit 31.)
      U8 left = random_u8(4 * n, 255, 1);
      U8 right = random_u8(4 * (n + D), 255, 3);
      for (auto [planes, pixels] : {std::pair{&left, n}, std::pair{&right, n + D}}) {
        for (std::size_t x = 0; x < pixels; ++x) (*planes)[3 * pixels + x] &= 0x7F;
      }
      for (const int bits : {kernels::kCensusBits, kernels::kSparseCensusBits}) {
        U8 ref(n * D, 0);
        kernels::cost_row_ref(left.data(), right.data(), width, D, bits, ref.data());
        EXPECT_EQ(ref[1], bits) << "d = 1 at x = 0 is beyond the left border";
        EXPECT_LE(*std::max_element(ref.begin(), ref.end()), bits);
        for (const SimdPath path : simd_paths()) {
          const auto simd = kernels::stereo_kernels(path);
          const U8 l = in_layout(left, width, simd.census_layout, 3);
          const U8 r = in_layout(right, width + D, simd.census_layout, 5);
          U8 out(n * D, 1);
          simd.cost(l.data() + 3, r.data() + 5, width, D, bits, out.data());
          ASSERT_EQ(out, ref) << to_string(path) << " width " << width << " D " << D << " bits "
                              << bits;
        }
      }
    }
  }
}

// The outputs of a winner take all, filled with a value the kernels never write (the
// confidence: one they write only where a winner's cost curve says so). Without
// `confidence_wanted` the kernel is given none to write.
struct WtaOut {
  WtaOut(std::size_t width, int D, bool confidence_wanted = true)
      : disparity(width, 99),
        best(width, 99),
        right_best(width, 99),
        window(2 * (width + static_cast<std::size_t>(D)), 7),
        confidence(width, 77),
        with_confidence(confidence_wanted) {}
  kernels::WtaRow row(int uniqueness) {
    return {uniqueness,        disparity.data(), best.data(),
            right_best.data(), window.data(),    with_confidence ? confidence.data() : nullptr};
  }
  I16 disparity, best, right_best;
  U16 window;
  U8 confidence;
  bool with_confidence;
};

// `ref` always has a confidence.
void expect_same_wta(const WtaOut& out, const WtaOut& ref, const std::string& where) {
  ASSERT_EQ(out.disparity, ref.disparity) << where;
  ASSERT_EQ(out.best, ref.best) << where;
  ASSERT_EQ(out.right_best, ref.right_best) << where;
  if (out.with_confidence) {
    ASSERT_EQ(out.confidence, ref.confidence) << where;
  } else {
    ASSERT_EQ(out.confidence, U8(out.confidence.size(), 77)) << where << ": none was asked for";
  }
  for (std::size_t x = 0; x < ref.best.size(); ++x) {
    if (ref.best[x] < 0) {
      ASSERT_EQ(ref.confidence[x], 0) << where << " x " << x;
    }
  }
}

// Three rows of aggregation: path state carried from row to row must agree too, and so must
// each row's winners. 64, 128 and 256 have kernels of their own (their loops unrolled).
TEST(StereoKernels, SgmEqualsReference) {
  for (const int width : {17, 33, 70, 300}) {
    for (const int D : {16, 32, 48, 64, 128, 256}) {
      const auto n = static_cast<std::size_t>(width);
      const std::size_t stride = static_cast<std::size_t>(D) + 32;
      struct State {
        U8 paths[2][3];
        U8 mins[2][3];
        U8 scratch;
        U16 sums;
      };
      const auto make_state = [&] {
        State s;
        for (auto& row : s.paths) {
          for (auto& p : row) {
            p.assign((n + 2) * stride, 0);
            for (std::size_t x = 0; x < n; ++x) {
              p[(x + 1) * stride + 15] = kernels::kSgmPad;
              p[(x + 1) * stride + 16 + static_cast<std::size_t>(D)] = kernels::kSgmPad;
            }
          }
        }
        for (auto& row : s.mins) {
          for (auto& m : row) m.assign(n + 2, 0);
        }
        s.scratch.assign(2 * stride, 3);
        s.sums.assign(n * D, 5);
        return s;
      };
      const auto run = [&](kernels::SgmRowKernel* kernel, State& s, WtaOut& out, const U8& cost,
                           int p1, int p2, int uniqueness, int prev) {
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
        row.wta = out.row(uniqueness);
        kernel(row);
      };
      for (const SimdPath path : simd_paths()) {
        for (const auto& [p1, p2] :
             {std::pair{11, 120}, std::pair{1, 1}, std::pair{30, kernels::kMaxSgmP2}}) {
          // Costs 0..31 as the census gives them, or 0..1: sums equal in many lanes and
          // blocks, so the winner is the smallest of many equal minima.
          for (const auto& [uniqueness, max_cost] :
               {std::pair{0, 31}, std::pair{10, 31}, std::pair{0, 1}}) {
            State ref = make_state();
            State simd = make_state();
            int prev = 0;
            for (int y = 0; y < 3; ++y) {
              // On the last row, the largest cost everywhere.
              U8 cost = random_u8(n * D, max_cost, static_cast<std::uint32_t>(y + 10 * D));
              if (y == 2) std::fill(cost.begin(), cost.begin() + D * 3, std::uint8_t{31});
              WtaOut ref_out(n, D), out(n, D, y != 1);
              run(kernels::sgm_row_ref, ref, ref_out, cost, p1, p2, uniqueness, prev);
              run(kernels::stereo_kernels(path).sgm, simd, out, cost, p1, p2, uniqueness, prev);
              prev = 1 - prev;
              const std::string where = cat(to_string(path), " row ", y, " p2 ", p2);
              expect_same_wta(out, ref_out, where);
              for (int k = 0; k < 3; ++k) {
                ASSERT_EQ(simd.paths[prev][k], ref.paths[prev][k]) << where;
                ASSERT_EQ(simd.mins[prev][k], ref.mins[prev][k]) << where;
              }
            }
          }
        }
      }
    }
  }
}

// A block-matching row of radius 0 with no row entering or leaving: the winner take all
// alone, on sums of every range; with max 3, many ties within a lane's eight values (each
// lane keeps its two smallest).
TEST(StereoKernels, WtaEqualsReference) {
  for (const int width : {17, 40}) {
    for (const int D : {16, 32, 64, 128}) {
      for (const int max : {3, 60, 2000, kernels::kNoCost - 1}) {
        for (const int uniqueness : {0, 5, 15, 99}) {
          const auto n = static_cast<std::size_t>(width);
          const U16 columns = random_u16(n * D, max, static_cast<std::uint32_t>(max + D));
          WtaOut ref(n, D);
          U16 ref_sums(n * D, 0), sums(n * D, 0);
          kernels::box_wta_ref(columns.data(), width, D, 0, ref_sums.data(), ref.row(uniqueness));
          for (const SimdPath path : simd_paths()) {
            WtaOut out(n, D, uniqueness != 5);
            U16 unchanged = columns;
            kernels::stereo_kernels(path).bm({nullptr, nullptr, unchanged.data(), width, D, 0,
                                              kernels::kCensusBits, sums.data(),
                                              out.row(uniqueness)});
            expect_same_wta(out, ref,
                            cat(to_string(path), " width ", width, " D ", D, " max ", max,
                                " uniqueness ", uniqueness));
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
      const U16 base = random_u16(n, 1000, 5);
      const U8 add = random_u8(n, 31, 6), sub = random_u8(n, 31, 7);
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
      }
    }
  }
}

// One row of block matching in one pass against box_columns + box_wta of the reference: the
// columns updated, the winners (64, 128 and 256 with both rows have kernels of their own).
TEST(StereoKernels, BmRowEqualsReference) {
  for (const auto& [width, D] :
       {std::pair{17, 16}, std::pair{40, 32}, std::pair{65, 48}, std::pair{70, 64},
        std::pair{131, 128}, std::pair{45, 256}, std::pair{300, 128}, std::pair{300, 256}}) {
    const auto n = static_cast<std::size_t>(width);
    U16 base = random_u16(n * D, 900, 23);
    for (auto& v : base) v = static_cast<std::uint16_t>(v + 100);  // a leaving row never wraps
    // The costs of either census.
    for (const int max_cost : {kernels::kCensusBits, kernels::kSparseCensusBits}) {
      const U8 entering = random_u8(n * D, max_cost, 24), leaving = random_u8(n * D, max_cost, 25);
      for (const SimdPath path : simd_paths()) {
        for (const int radius : {1, 3, 10}) {
          // A row between the first and the last, as BmRow promises it: each column the sum of
          // 2 * radius + 1 costs (max_cost to 2 * radius * max_cost here, so that a row entering
          // and one leaving keep it one), and beyond the left border (d > c) every cost
          // max_cost.
          const int column_max = (2 * radius + 1) * max_cost;
          U16 inner_base = base;
          U8 inner_entering = entering, inner_leaving = leaving;
          for (std::size_t c = 0; c < n; ++c) {
            for (std::size_t d = 0; d < static_cast<std::size_t>(D); ++d) {
              std::uint16_t& column = inner_base[c * D + d];
              if (d > c) {
                column = static_cast<std::uint16_t>(column_max);
                inner_entering[c * D + d] = inner_leaving[c * D + d] =
                    static_cast<std::uint8_t>(max_cost);
              } else {
                column =
                    static_cast<std::uint16_t>(max_cost + column % (column_max - 2 * max_cost + 1));
              }
            }
          }
          for (const bool enters : {false, true}) {
            for (const bool leaves : {false, true}) {
              const bool inner = enters && leaves;
              for (const bool confidence : {false, true}) {
                const auto run = [&](kernels::BmRowKernel* kernel, U16& columns, WtaOut& out) {
                  U16 sums(n * D, 3);
                  kernel({enters ? (inner ? inner_entering : entering).data() : nullptr,
                          leaves ? (inner ? inner_leaving : leaving).data() : nullptr,
                          columns.data(), width, D, radius, max_cost, sums.data(), out.row(10)});
                };
                U16 ref_columns = inner ? inner_base : base, columns = ref_columns;
                WtaOut ref(n, D), out(n, D, confidence);
                run(kernels::bm_row_ref, ref_columns, ref);
                run(kernels::stereo_kernels(path).bm, columns, out);
                const std::string where =
                    cat(to_string(path), " width ", width, " radius ", radius, " max cost ",
                        max_cost, " enters ", enters, " leaves ", leaves);
                ASSERT_EQ(columns, ref_columns) << where;
                expect_same_wta(out, ref, where);
              }
            }
          }
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
  if (config.confidence) {  // after the disparities: the winners' margins over every other cost
    const auto c = matcher.confidence();
    for (int y = 0; y < c.height(); ++y) out.insert(out.end(), c.row(y), c.row(y) + c.width());
  }
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
    // 64: a range with kernels of its own, and block matching's left band.
    for (const auto& [threads, D] :
         {std::pair{1, 16}, std::pair{2, 16}, std::pair{1, 32}, std::pair{1, 64}}) {
      StereoConfig config{.width = width, .height = height, .max_disparity = D};
      config.method = method;
      config.threads = threads;
      config.speckle_size = 4;
      config.confidence = true;  // it reads every block's sums, the ones a pixel cannot win too
      const auto ref = disparities(config, SimdPath::reference, left.cview(), right.cview());
      for (const SimdPath path : simd_paths()) {
        EXPECT_EQ(disparities(config, path, left.cview(), right.cview()), ref)
            << to_string(path) << " threads " << threads;
      }
      // The blobs' disparity (5..7 px) is found somewhere.
      const auto pixels = static_cast<long>(width) * height;
      const long found = std::count_if(ref.begin(), ref.begin() + pixels, [](std::int16_t d) {
        return d >= 5 * kDisparityScale - 8 && d <= 7 * kDisparityScale + 8;
      });
      EXPECT_GT(found, pixels / 3) << "threads " << threads;
      if (method == StereoMethod::bm && threads == 2) {  // D 16
        config.threads = 1;
        EXPECT_EQ(disparities(config, SimdPath::reference, left.cview(), right.cview()), ref)
            << "block matching does not depend on the stripes";
      }
    }
  }
}

// Stripes without a row of their own (more threads than rows) write nothing: SGM's warm-up
// would otherwise put its winners into the next stripe's first row while that stripe runs.
TEST(StereoMatcher, MoreStripesThanRowsGiveWhatOneStripeGives) {
  const int width = 48;
  const int height = 8;
  test::BufferImage left(width, height, width, 1);
  test::fill(left.view(), test::Pattern::blobs, 5);
  test::BufferImage right(width, height, width, 2);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x)
      right.view()(x, y) = left.cview()(std::min(width - 1, x + 4), y);
  }
  for (const StereoMethod method : {StereoMethod::sgm, StereoMethod::bm}) {
    StereoConfig config{.width = width, .height = height, .max_disparity = 16};
    config.method = method;
    const auto one = disparities(config, SimdPath::reference, left.cview(), right.cview());
    config.threads = 13;
    for (const SimdPath path : simd_paths()) {
      for (int run = 0; run < 5; ++run) {
        EXPECT_EQ(disparities(config, path, left.cview(), right.cview()), one)
            << to_string(path) << (method == StereoMethod::sgm ? " sgm" : " bm");
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
  EXPECT_NE(message([] {
              StereoMatcher m({.width = 640, .height = 48, .p1 = 11, .p2 = 225});
            }).find("P2 225 must satisfy 1 <= P1 <= P2 <= 224"),
            std::string::npos)
      << "8-bit path values need max cost + P2 <= 255";
  EXPECT_NE(message([] {
              StereoConfig config{.width = 64, .height = 48, .max_disparity = 16};
              config.speckle_range = 256;
              StereoMatcher m(config);
            }).find("speckle range 256 px: expected 0..255"),
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
