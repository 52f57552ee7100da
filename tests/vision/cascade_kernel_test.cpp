// The cascade detector's kernels, every path against the scalar reference bit for bit (odd
// widths, unaligned rows, the minimum sizes), the references against their definitions, and
// whole detections (random Haar, tilted, LBP and tree cascades on odd-sized images, raw hits
// and grouped boxes) identical on every path; detector behaviour and bad configurations.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "cascade_kernels.hpp"
#include "cascade_program.hpp"
#include "cascade_test_models.hpp"
#include "epipole/core/error.hpp"
#include "epipole/core/thread_pool.hpp"
#include "epipole/vision/cascade.hpp"
#include "random_image.hpp"

namespace epipole::vision {
namespace {

std::vector<std::uint8_t> random_bytes(std::size_t n, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::vector<std::uint8_t> v(n);
  for (auto& b : v) b = static_cast<std::uint8_t>(rng() % 3 == 0 ? 255 * (rng() & 1) : rng());
  return v;
}

std::vector<std::uint32_t> random_words(std::size_t n, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::vector<std::uint32_t> v(n);
  for (auto& w : v) w = static_cast<std::uint32_t>(rng());
  return v;
}

TEST(CascadeKernels, IntegralRowsEqualReferenceAndDefinition) {
  for (int width = 1; width <= 70; width += width < 20 ? 1 : 7) {
    for (const std::size_t offset : {std::size_t{0}, std::size_t{1}, std::size_t{3}}) {
      const auto row = random_bytes(width + offset, static_cast<std::uint32_t>(width));
      const auto above =
          random_words(2 * (width + 1) + offset, static_cast<std::uint32_t>(width + 7));
      const std::uint32_t* sum_above = above.data() + offset;
      const std::uint32_t* square_above = sum_above + width + 1;
      // The definition.
      std::vector<std::uint32_t> sum(width + 1), square(width + 1), prefix(width + 2);
      std::uint32_t s = 0, q = 0;
      for (int x = 0; x <= width; ++x) {
        sum[x] = sum_above[x] + s;
        square[x] = square_above[x] + q;
        prefix[x + 1] = s;
        if (x < width) s += row[offset + x], q += row[offset + x] * row[offset + x];
      }
      prefix[0] = 0;
      for (const SimdPath path : available_simd_paths()) {
        for (const int variant : {0, 1, 2}) {  // plain, with the prefix, without squares
          const bool with_prefix = variant == 1;
          const bool with_squares = variant != 2;
          std::vector<std::uint32_t> out(3 * (width + 2) + offset, 0xDEADBEEF);
          std::uint32_t* out_sum = out.data() + offset;
          std::uint32_t* out_square = out_sum + width + 1;
          std::uint32_t* out_prefix = out_square + width + 1;
          kernels::integral_row_kernel(path)(
              row.data() + offset, width, sum_above, with_squares ? square_above : nullptr, out_sum,
              with_squares ? out_square : nullptr, with_prefix ? out_prefix : nullptr);
          for (int x = 0; x <= width; ++x) {
            ASSERT_EQ(out_sum[x], sum[x]) << to_string(path) << " width " << width << " x " << x;
            ASSERT_EQ(out_square[x], with_squares ? square[x] : 0xDEADBEEF)
                << to_string(path) << " x " << x;
          }
          for (int x = 0; x < width + 2; ++x) {
            ASSERT_EQ(out_prefix[x], with_prefix ? prefix[x] : 0xDEADBEEF)
                << to_string(path) << " prefix " << x;
          }
        }
      }
    }
  }
}

// OpenCV's tilted integral, summed pixel by pixel: T(X, Y) = sum of I(x, y) over y < Y and
// |x - (X - 1)| <= Y - 1 - y.
std::uint32_t tilted_definition(const std::vector<std::uint8_t>& image, int width, int X, int Y) {
  std::uint32_t t = 0;
  for (int y = 0; y < Y; ++y) {
    for (int x = 0; x < width; ++x) {
      if (std::abs(x - (X - 1)) <= Y - 1 - y) t += image[static_cast<std::size_t>(y) * width + x];
    }
  }
  return t;
}

TEST(CascadeKernels, TiltedRowsEqualReferenceAndDefinition) {
  for (const int width : {1, 2, 3, 4, 5, 7, 8, 9, 13, 16, 31, 33}) {
    const int height = 11;
    const auto image =
        random_bytes(static_cast<std::size_t>(width) * height, static_cast<std::uint32_t>(width));
    for (const SimdPath path : available_simd_paths()) {
      std::vector<std::uint32_t> rows(4 * (width + 2), 0);
      std::vector<std::uint32_t> sums(2 * (width + 1), 0), prefix(width + 2), tilted(width + 1);
      for (int y = 0; y < height; ++y) {
        std::uint32_t* sum = &sums[(y & 1) * (width + 1)];
        std::uint32_t* next = &sums[(1 - (y & 1)) * (width + 1)];
        kernels::integral_row_ref(&image[static_cast<std::size_t>(y) * width], width, sum, sum,
                                  next, next, prefix.data());
        std::uint32_t* from = &rows[(y & 1) * 2 * (width + 2)];
        std::uint32_t* to = &rows[(1 - (y & 1)) * 2 * (width + 2)];
        kernels::tilted_row_kernel(path)(prefix.data(), width, from, from + width + 2, to,
                                         to + width + 2, tilted.data());
        for (int x = 0; x <= width; ++x) {
          ASSERT_EQ(tilted[x], tilted_definition(image, width, x, y + 1))
              << to_string(path) << " width " << width << " at " << x << "," << y + 1;
        }
      }
    }
  }
}

TEST(CascadeKernels, ResizeCoefficientsFollowTheDefinition) {
  std::vector<std::int32_t> offsets(600);
  std::vector<std::uint16_t> weights(1200);
  for (const auto& [source, size] :
       std::vector<std::pair<int, int>>{{100, 50}, {548, 498}, {7, 3}, {1, 5}, {9, 20}, {33, 33}}) {
    kernels::resize_coefficients(source, size, offsets.data(), weights.data());
    for (int i = 0; i < size; ++i) {
      const double f = (i + 0.5) * (1.0 / (static_cast<double>(size) / source)) - 0.5;
      const int whole = static_cast<int>(std::floor(f));
      EXPECT_EQ(weights[2 * i] + weights[2 * i + 1], 256);
      if (whole < 0 || source == 1) {
        EXPECT_EQ(offsets[i], 0);
        EXPECT_EQ(weights[2 * i], 256);
      } else if (whole >= source - 1) {
        EXPECT_EQ(offsets[i], source - 1);
        EXPECT_EQ(weights[2 * i], 256);
      } else {
        EXPECT_EQ(offsets[i], whole);
        EXPECT_EQ(weights[2 * i + 1], std::lrint((f - whole) * 256));
      }
    }
  }
  // An exact half: every pixel blends two source pixels equally.
  kernels::resize_coefficients(100, 50, offsets.data(), weights.data());
  EXPECT_EQ(offsets[7], 14);
  EXPECT_EQ(weights[14], 128);
}

TEST(CascadeKernels, ResizeRowsEqualReferenceAndDefinition) {
  std::mt19937 rng(3);
  for (int source = 1; source <= 90; source += source < 20 ? 1 : 11) {
    for (const int width : {1, 5, 8, 9, 17, source, source / 2 + 1, 2 * source}) {
      const auto row = random_bytes(static_cast<std::size_t>(source) + 1,
                                    static_cast<std::uint32_t>(source + width));
      std::vector<std::int32_t> offsets(width);
      std::vector<std::uint16_t> weights(2 * width);
      kernels::resize_coefficients(source, width, offsets.data(), weights.data());
      std::vector<std::uint16_t> expected(width);
      for (int x = 0; x < width; ++x) {
        const int o = offsets[x];
        expected[x] = static_cast<std::uint16_t>(
            row[o] * weights[2 * x] + (o + 1 < source ? row[o + 1] * weights[2 * x + 1] : 0));
      }
      const std::vector<std::uint16_t> other(width, static_cast<std::uint16_t>(rng() % 65281));
      const std::uint16_t w1 = static_cast<std::uint16_t>(rng() % 257);
      for (const SimdPath path : available_simd_paths()) {
        std::vector<std::uint16_t> columns(width + 1, 0xBEEF);
        kernels::resize_columns_kernel(path)(row.data(), source, offsets.data(), weights.data(),
                                             width, columns.data() + 1);
        for (int x = 0; x < width; ++x) {
          ASSERT_EQ(columns[x + 1], expected[x])
              << to_string(path) << " " << source << " -> " << width;
        }
        EXPECT_EQ(columns[0], 0xBEEF);
        std::vector<std::uint8_t> out(width + 2, 0x5A);
        kernels::resize_rows_kernel(path)(columns.data() + 1, other.data(),
                                          static_cast<std::uint16_t>(256 - w1), w1, width,
                                          out.data() + 1);
        for (int x = 0; x < width; ++x) {
          const unsigned v = (expected[x] * (256u - w1) + other[x] * unsigned{w1} + 32768) >> 16;
          ASSERT_EQ(out[x + 1], v) << to_string(path) << " column " << x;
        }
        EXPECT_EQ(out[0], 0x5A);
        EXPECT_EQ(out[width + 1], 0x5A);
      }
    }
  }
}

// A configuration that returns every raw hit of images up to width x height with `model`: room
// for one at each window of every level (a level is at most a pixel wider and higher than the
// image over its scale). Not more: under ThreadSanitizer each detector's zeroed hit lists were
// most of this program's time.
CascadeConfig raw_config(int width, int height, const CascadeModel& model,
                         double scale_factor = CascadeConfig{}.scale_factor) {
  CascadeConfig config;
  config.max_width = width;
  config.max_height = height;
  config.min_neighbors = 0;
  config.scale_factor = scale_factor;
  long windows = 0;
  for (double factor = 1;; factor *= scale_factor) {
    const int columns = static_cast<int>(width / factor) + 2 - model.window_width();
    const int rows = static_cast<int>(height / factor) + 2 - model.window_height();
    if (columns <= 0 || rows <= 0) break;
    windows += static_cast<long>(columns) * rows;
  }
  config.max_raw_hits = config.max_detections = static_cast<int>(std::max(windows, 1L));
  return config;
}

struct DetectionCase {
  const char* name;
  test::RandomCascadeShape shape;
  int width;
  int height;
  std::size_t min_hits = 20;  // windows that pass, over both images and all scale factors
  std::uint32_t seed = 21;
};

void PrintTo(const DetectionCase& c, std::ostream* out) {
  *out << c.name;
}

class CascadeDetection : public ::testing::TestWithParam<DetectionCase> {};

// Whole detections: the raw hits and the grouped boxes of every path equal the reference's, on
// images with sizes that give odd level widths, for several scale factors.
TEST_P(CascadeDetection, EveryPathFindsTheSameWindows) {
  const DetectionCase& c = GetParam();
  const CascadeModel model(test::random_cascade(c.shape, c.seed), c.name);
  if (c.shape.edge_features) {  // the kernels' six-corner stumps are what this case tests
    const kernels::CascadeProgram program(model, {128, 0}, 128 * 30, 128 * 60);
    int six_corner_stumps = 0;
    for (const kernels::ProgramStage& stage : program.stages) six_corner_stumps += stage.six_count;
    EXPECT_TRUE(program.integer_weights);
    EXPECT_GT(six_corner_stumps, 0);
  }
  ThreadPool pool(3);
  std::size_t total_hits = 0;
  for (const test::Pattern pattern : {test::Pattern::blobs, test::Pattern::noise}) {
    test::BufferImage image(c.width, c.height, c.width + 3, 1);
    test::fill(image.view(), pattern, static_cast<std::uint32_t>(c.width));
    for (const double scale : {1.1, 1.25, 2.0}) {
      CascadeConfig config = raw_config(c.width, c.height, model, scale);
      CascadeDetector reference(model, config, SimdPath::reference);
      reference.detect(image.cview());
      ASSERT_FALSE(reference.truncated()) << c.name << " scale " << scale;
      const std::vector<Detection> expected(reference.raw_hits().begin(),
                                            reference.raw_hits().end());
      total_hits += expected.size();
      config.min_neighbors = 2;
      CascadeDetector grouped_reference(model, config, SimdPath::reference);
      const auto grouped = grouped_reference.detect(image.cview());
      const std::vector<Detection> expected_grouped(grouped.begin(), grouped.end());
      for (const SimdPath path : available_simd_paths()) {
        config.min_neighbors = 0;
        CascadeDetector detector(model, config, path);
        detector.detect(image.cview());
        EXPECT_EQ(std::vector<Detection>(detector.raw_hits().begin(), detector.raw_hits().end()),
                  expected)
            << c.name << " " << to_string(path) << " scale " << scale;
        EXPECT_EQ(detector.simd_windows(), path != SimdPath::reference && model.stump_based());
        config.min_neighbors = 2;
        CascadeDetector grouping(model, config, path);
        const auto boxes = grouping.detect(image.cview());
        EXPECT_EQ(std::vector<Detection>(boxes.begin(), boxes.end()), expected_grouped)
            << c.name << " " << to_string(path);
        // The levels searched by three workers at once: the same hits in the same order, the
        // same boxes; and with a bound on the raw hits that cuts them, the same cut.
        // (An eighth: small enough that the workers' own lists fill as well.)
        for (const int bound : {config.max_raw_hits, static_cast<int>(expected.size() / 2),
                                static_cast<int>(expected.size() / 8)}) {
          if (bound < 1) continue;
          CascadeConfig pooled_config = config;
          pooled_config.workers = 3;
          pooled_config.max_raw_hits = bound;
          CascadeDetector pooled(model, pooled_config, path);
          const int levels = pooled.start(image.cview());
          pool.run(levels, [&](int level, int worker) { pooled.search_level(level, worker); });
          const auto pooled_boxes = pooled.finish();
          const std::size_t kept = std::min(expected.size(), static_cast<std::size_t>(bound));
          EXPECT_EQ(std::vector<Detection>(pooled.raw_hits().begin(), pooled.raw_hits().end()),
                    std::vector<Detection>(expected.begin(),
                                           expected.begin() + static_cast<std::ptrdiff_t>(kept)))
              << c.name << " " << to_string(path) << " bound " << bound;
          EXPECT_EQ(pooled.truncated(), kept < expected.size());
          if (kept == expected.size()) {
            EXPECT_EQ(std::vector<Detection>(pooled_boxes.begin(), pooled_boxes.end()),
                      expected_grouped);
          }
        }
      }
    }
  }
  EXPECT_GE(total_hits, c.min_hits)
      << "windows must pass every stage for the test to mean something";
}

test::RandomCascadeShape shape(CascadeFeatureType type, int w, int h, int nodes, bool tilted,
                               double pass_rate = 0.75, bool fractional_weights = false,
                               bool edge_features = false) {
  test::RandomCascadeShape s;
  s.fractional_weights = fractional_weights;
  s.edge_features = edge_features;
  s.pass_rate = pass_rate;
  s.type = type;
  s.window_width = w;
  s.window_height = h;
  s.max_nodes = nodes;
  s.tilted = tilted;
  return s;
}

INSTANTIATE_TEST_SUITE_P(
    Cascades, CascadeDetection,
    ::testing::Values(
        DetectionCase{"haar_stumps", shape(CascadeFeatureType::haar, 24, 24, 1, false), 97, 71},
        DetectionCase{"haar_tilted", shape(CascadeFeatureType::haar, 20, 24, 1, true), 83, 64},
        DetectionCase{"haar_edge_features",
                      shape(CascadeFeatureType::haar, 24, 24, 1, false, 0.75, false, true), 91, 69},
        DetectionCase{"haar_tilted_edge_features",
                      shape(CascadeFeatureType::haar, 24, 24, 1, true, 0.75, false, true), 91, 69,
                      20, 22},
        DetectionCase{"haar_fractional_weights",
                      shape(CascadeFeatureType::haar, 24, 24, 1, true, 0.9, true), 89, 67},
        DetectionCase{"haar_trees", shape(CascadeFeatureType::haar, 20, 20, 3, true), 61, 45},
        DetectionCase{"lbp", shape(CascadeFeatureType::lbp, 24, 24, 1, false), 101, 77},
        DetectionCase{"lbp_small_window", shape(CascadeFeatureType::lbp, 9, 12, 1, false), 33, 29},
        DetectionCase{"haar_minimum_image", shape(CascadeFeatureType::haar, 24, 24, 1, false), 24,
                      24, 2}),
    [](const ::testing::TestParamInfo<DetectionCase>& p) { return std::string(p.param.name); });

// The SIMD kernels' stumps: a stage's grouped by kind (a rectangle and its half as six corners),
// integer weights where OpenCV's cascades have them, and each stage's deltas split into 32-bit
// parts that add up to the same fixed-point sums without overflow.
TEST(CascadeProgram, StumpsForTheSimdKernels) {
  for (const bool fractional : {false, true}) {
    for (const bool tilted : {false, true}) {
      const CascadeModel model(
          test::random_cascade(
              shape(CascadeFeatureType::haar, 24, 24, 1, tilted, 0.75, fractional, true), 7),
          "random");
      const kernels::CascadeProgram p(model, {64, 0}, 64 * 30, 64 * 60);
      ASSERT_TRUE(p.fixed_point_exact);
      EXPECT_EQ(p.integer_weights, !fractional);
      std::size_t next = 0;
      int six_corner_stumps = 0;
      for (const kernels::ProgramStage& stage : p.stages) {
        int pairs = 0;
        std::int64_t expected = 0;
        for (int k = 0; k < stage.weak_count; ++k) {
          const int i = stage.first_weak + k;
          pairs += p.haar[static_cast<std::size_t>(p.nodes[i].feature)].rect_count == 2 ? 1 : 0;
          expected += static_cast<std::int64_t>(std::ldexp(p.leaves[2 * i], p.fixed_shift)) -
                      static_cast<std::int64_t>(std::ldexp(p.leaves[2 * i + 1], p.fixed_shift));
        }
        EXPECT_EQ(stage.six_count + stage.pair_count, pairs);
        if (fractional) {
          EXPECT_EQ(stage.six_count, 0);
        }
        six_corner_stumps += stage.six_count;
        const std::int64_t unit = std::int64_t{1} << stage.split_shift;
        // The largest shift for which the low parts' sum fits.
        EXPECT_LE(stage.weak_count * (unit - 1), std::int64_t{INT32_MAX});
        EXPECT_GT(stage.weak_count * (2 * unit - 1), std::int64_t{INT32_MAX});
        std::int64_t sum = 0;
        std::int64_t high_magnitude = 0;
        for (int k = 0; k < stage.weak_count; ++k, ++next) {
          const kernels::HaarStump& s = p.haar_stumps[next];
          const std::int32_t low = s.params.words[kernels::StumpParams::kDeltaLow];
          const std::int32_t high = s.params.words[kernels::StumpParams::kDeltaHigh];
          EXPECT_GE(low, 0);
          EXPECT_LT(low, unit);
          sum += high * unit + low;
          high_magnitude += std::abs(high);
        }
        EXPECT_LE(high_magnitude, std::int64_t{INT32_MAX});
        EXPECT_EQ(sum, expected);
      }
      EXPECT_EQ(next, p.haar_stumps.size());
      if (!fractional) {
        EXPECT_GT(six_corner_stumps, 0) << "a rectangle and its half share two corners";
      }
    }
  }
}

// A stage whose high parts could overflow 32 bits (thousands of stumps with leaves of very
// different sizes) leaves the cascade to the reference kernel, whose double sums are exact.
TEST(CascadeProgram, HugeStagesFallBackToTheReference) {
  CascadeData d;
  d.window_width = d.window_height = 24;
  HaarFeature f;
  f.rect_count = 2;
  f.rects[0] = {0, 0, 24, 24, -1.0f};
  f.rects[1] = {0, 0, 12, 24, 2.0f};
  d.haar_features.push_back(f);
  const int stumps = 8000;
  d.stages.push_back({stumps, 0.0f});
  for (int i = 0; i < stumps; ++i) {
    d.node_counts.push_back(1);
    d.nodes.push_back({0, -1, 0, 0.0f});
    // Leaves of 1 and -1, and one of 2^-13, which makes the unit 2^-36: deltas of 2^37.
    d.leaves.push_back(1.0f);
    d.leaves.push_back(i == 0 ? 0x1p-13f : -1.0f);
  }
  const CascadeModel model(d, "huge");
  const kernels::CascadeProgram p(model, {64, 0}, 64 * 30, 64 * 60);
  EXPECT_FALSE(p.fixed_point_exact);
  EXPECT_TRUE(p.haar_stumps.empty());
  // With a tenth of the stumps it fits.
  d.stages[0].weak_count = stumps / 10;
  d.node_counts.resize(stumps / 10);
  d.nodes.resize(stumps / 10);
  d.leaves.resize(2 * (stumps / 10));
  const CascadeModel smaller(d, "smaller");
  EXPECT_TRUE(kernels::CascadeProgram(smaller, {64, 0}, 64 * 30, 64 * 60).fixed_point_exact);
}

TEST(CascadeDetector, BoundsAndLimits) {
  const CascadeModel model(
      test::random_cascade(shape(CascadeFeatureType::haar, 24, 24, 1, false, 0.68), 4), "random");
  GrayImage image(120, 90);
  test::fill(image.view(), test::Pattern::blobs, 5);
  CascadeConfig config = raw_config(120, 90, model);
  CascadeDetector unbounded(model, config, SimdPath::reference);
  const std::size_t all = unbounded.detect(image.view()).size();
  ASSERT_GT(all, 10u);
  EXPECT_FALSE(unbounded.truncated());
  EXPECT_GT(unbounded.levels(), 5);
  config.max_raw_hits = 10;
  CascadeDetector bounded(model, config, best_simd_path());
  EXPECT_EQ(bounded.raw_hits().size(), 0u);
  EXPECT_EQ(bounded.detect(image.view()).size(), 10u);
  EXPECT_TRUE(bounded.truncated());
  // Minimum and maximum sizes select levels: only windows in [40, 60] remain.
  config.max_raw_hits = 100'000;
  config.min_object_width = config.min_object_height = 40;
  config.max_object_width = config.max_object_height = 60;
  CascadeDetector sized(model, config);
  for (const Detection& d : sized.detect(image.view())) {
    EXPECT_GE(d.width, 40);
    EXPECT_LE(d.width, 60);
  }
  EXPECT_EQ(sized.levels(), 4) << "windows of 43, 47, 51 and 57 (24 times 1.1^6 .. 1.1^9)";
  // Smaller images than the configured size are fine; larger ones are an error.
  EXPECT_NO_THROW(unbounded.detect(image.view().sub(0, 0, 50, 40)));
  EXPECT_TRUE(unbounded.detect(image.view().sub(0, 0, 20, 20)).empty());
  EXPECT_EQ(unbounded.levels(), 0);
  GrayImage big(121, 90);
  EXPECT_THROW(unbounded.detect(big.view()), Error);
}

TEST(CascadeDetector, BadConfigurationsAreErrors) {
  const CascadeModel model(
      test::random_cascade(shape(CascadeFeatureType::lbp, 24, 24, 1, false), 4), "random");
  const auto make = [&model](auto change) {
    CascadeConfig config;
    config.max_width = 64;
    config.max_height = 48;
    change(config);
    return CascadeDetector(model, config);
  };
  EXPECT_NO_THROW(make([](CascadeConfig&) {}));
  EXPECT_THROW(make([](CascadeConfig& c) { c.max_width = 0; }), Error);
  EXPECT_THROW(make([](CascadeConfig& c) { c.scale_factor = 1.0; }), Error);
  EXPECT_THROW(make([](CascadeConfig& c) { c.scale_factor = std::nan(""); }), Error);
  EXPECT_THROW(make([](CascadeConfig& c) { c.min_neighbors = -1; }), Error);
  EXPECT_THROW(make([](CascadeConfig& c) { c.min_object_width = -5; }), Error);
  EXPECT_THROW(make([](CascadeConfig& c) { c.max_raw_hits = 0; }), Error);
  EXPECT_THROW(make([](CascadeConfig& c) { c.max_detections = 0; }), Error);
}

// cv::groupRectangles written plainly: classes are the connected components of "similar"
// (grown by breadth-first search), numbered by their first member; each class's average is
// rounded as OpenCV does (float reciprocal, ties to even); classes with at most min_neighbors
// members go, and so do those inside a bigger class with more members; then the image clip.
std::vector<Detection> group_definition(const std::vector<Detection>& raw, int min_neighbors,
                                        int width, int height) {
  const auto similar = [](const Detection& a, const Detection& b) {
    const double delta = 0.2 * (std::min(a.width, b.width) + std::min(a.height, b.height)) * 0.5;
    return std::abs(a.x - b.x) <= delta && std::abs(a.y - b.y) <= delta &&
           std::abs(a.x + a.width - b.x - b.width) <= delta &&
           std::abs(a.y + a.height - b.y - b.height) <= delta;
  };
  std::vector<int> label(raw.size(), -1);
  std::vector<Detection> classes;
  for (std::size_t i = 0; i < raw.size(); ++i) {
    if (label[i] >= 0) continue;
    const int id = static_cast<int>(classes.size());
    std::vector<std::size_t> queue{i};
    label[i] = id;
    long sx = 0, sy = 0, sw = 0, sh = 0;
    int n = 0;
    for (std::size_t q = 0; q < queue.size(); ++q) {
      const Detection& r = raw[queue[q]];
      sx += r.x, sy += r.y, sw += r.width, sh += r.height, ++n;
      for (std::size_t j = 0; j < raw.size(); ++j) {
        if (label[j] < 0 && similar(r, raw[j])) label[j] = id, queue.push_back(j);
      }
    }
    const float s = 1.0f / static_cast<float>(n);
    const auto round = [s](long v) {
      return static_cast<int>(std::lrint(static_cast<float>(v) * s));
    };
    classes.push_back({round(sx), round(sy), round(sw), round(sh), n});
  }
  std::vector<Detection> out;
  for (std::size_t i = 0; i < classes.size(); ++i) {
    const Detection& a = classes[i];
    if (a.neighbors <= min_neighbors) continue;
    bool inside = false;
    for (std::size_t j = 0; j < classes.size(); ++j) {
      const Detection& b = classes[j];
      if (j == i || b.neighbors <= min_neighbors) continue;
      const int dx = static_cast<int>(std::lrint(b.width * 0.2));
      const int dy = static_cast<int>(std::lrint(b.height * 0.2));
      inside =
          inside || (a.x >= b.x - dx && a.y >= b.y - dy && a.x + a.width <= b.x + b.width + dx &&
                     a.y + a.height <= b.y + b.height + dy &&
                     (b.neighbors > std::max(3, a.neighbors) || a.neighbors < 3));
    }
    if (inside) continue;
    const int x0 = std::max(a.x, 0), y0 = std::max(a.y, 0);
    const int x1 = std::min(a.x + a.width, width), y1 = std::min(a.y + a.height, height);
    if (x1 > x0 && y1 > y0) out.push_back({x0, y0, x1 - x0, y1 - y0, a.neighbors});
  }
  return out;
}

TEST(CascadeDetector, GroupsLikeGroupRectangles) {
  // Random cascades that pass a few hundred to a few thousand windows of their image.
  for (const std::uint32_t seed : {1u, 5u}) {
    const CascadeModel model(
        test::random_cascade(shape(CascadeFeatureType::haar, 24, 24, 1, false, 0.75), seed),
        "random");
    GrayImage image(200, 150);
    test::fill(image.view(), test::Pattern::blobs, seed);
    CascadeConfig config = raw_config(200, 150, model);
    CascadeDetector raw_detector(model, config, SimdPath::reference);
    const std::span<const Detection> hits = raw_detector.detect(image.view());
    const std::vector<Detection> raw(hits.begin(), hits.end());
    ASSERT_GT(raw.size(), 100u) << "seed " << seed;
    for (const int min_neighbors : {1, 2, 3, 5}) {
      config.min_neighbors = min_neighbors;
      CascadeDetector detector(model, config, best_simd_path());
      const auto boxes = detector.detect(image.view());
      EXPECT_EQ(std::vector<Detection>(boxes.begin(), boxes.end()),
                group_definition(raw, min_neighbors, 200, 150))
          << "seed " << seed << " min_neighbors " << min_neighbors;
      EXPECT_FALSE(boxes.empty());
    }
  }
}

}  // namespace
}  // namespace epipole::vision
