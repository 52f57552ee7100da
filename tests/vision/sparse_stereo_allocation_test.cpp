// Fixed memory: sparse matching and the triangulation of its matches never allocate per frame.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <vector>

#include "../calib/sample_calibration.hpp"
#include "allocation_counter.hpp"
#include "epipole/firmware/sparse_points.hpp"
#include "epipole/vision/fast.hpp"
#include "epipole/vision/sparse_stereo.hpp"
#include "epipole/vision/window_matcher.hpp"
#include "random_image.hpp"

namespace epipole::vision {
namespace {

TEST(SparseAllocations, CounterSeesAllocations) {
  test::AllocationCounter counter;
  auto p = std::make_unique<int>(7);
  EXPECT_EQ(counter.count(), 1u)
      << "the counter must see a plain new, or the test below proves nothing";
}

TEST(SparseAllocations, MatchAndTriangulateNeverAllocate) {
  constexpr int kW = 640;
  constexpr int kH = 480;
  GrayImage left(kW, kH), right(kW, kH);
  test::fill(left.view(), test::Pattern::blobs, 1);
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) right.view()(x, y) = left.view()(std::min(x + 9, kW - 1), y);
  }
  FastDetector fast_left({.width = kW, .height = kH}), fast_right({.width = kW, .height = kH});
  const auto l = fast_left.detect(left.view());
  const auto r = fast_right.detect(right.view());
  const calib::Triangulator triangulator(test::sample_calibration());
  std::array<firmware::SparsePoint, 500> points{};
  for (const SimdPath path : available_simd_paths()) {
    SparseStereoMatcher matcher({.width = kW, .height = kH}, path);
    std::size_t found = 0;
    test::AllocationCounter counter;
    for (int frame = 0; frame < 100; ++frame) {
      const auto matches = matcher.match(left.view(), l, right.view(), r);
      found += firmware::triangulate_matches(triangulator, matches, points);
    }
    EXPECT_EQ(counter.count(), 0u) << to_string(path);
    EXPECT_GT(found, 100u * 100u) << "matches were made";
  }
  SparseStereoMatcher matcher({.width = kW, .height = kH});
  std::printf("sparse stereo 640x480, 4000 corners, 2000 matches: %zu bytes\n",
              matcher.working_set_bytes());
}

TEST(SparseAllocations, FollowingFeaturesNeverAllocates) {
  constexpr int kW = 640;
  constexpr int kH = 480;
  GrayImage a(kW, kH), b(kW, kH);
  test::fill(a.view(), test::Pattern::blobs, 2);
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) b.view()(x, y) = a.view()(std::max(x - 5, 0), std::max(y - 3, 0));
  }
  FastDetector fast_a({.width = kW, .height = kH}), fast_b({.width = kW, .height = kH});
  const auto ca = fast_a.detect(a.view());
  const auto cb = fast_b.detect(b.view());
  SparseStereoMatcher describe_a({.width = kW, .height = kH}),
      describe_b({.width = kW, .height = kH});
  describe_a.match(a.view(), ca, a.view(), ca);
  describe_b.match(b.view(), cb, b.view(), cb);
  const DescribedCorners from = describe_a.left_features();
  const DescribedCorners to = describe_b.left_features();
  const int n = std::min(from.count(), 2000);
  std::vector<float> x(static_cast<std::size_t>(n)), y(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    x[static_cast<std::size_t>(i)] = from.x[static_cast<std::size_t>(i)] + 5.0f;
    y[static_cast<std::size_t>(i)] = from.y[static_cast<std::size_t>(i)] + 3.0f;
  }
  const auto descriptors = from.descriptors.first(static_cast<std::size_t>(n) * 32);
  for (const SimdPath path : available_simd_paths()) {
    WindowMatcher matcher({.width = kW, .height = kH}, path);
    std::size_t found = 0;
    test::AllocationCounter counter;
    for (int frame = 0; frame < 5; ++frame) found += matcher.match(descriptors, x, y, to).size();
    EXPECT_EQ(counter.count(), 0u) << to_string(path);
    EXPECT_GT(found, 0u);
  }
}

}  // namespace
}  // namespace epipole::vision
