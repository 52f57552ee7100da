// Features followed into a later image (vision/window_matcher.hpp): an image moved by a known
// shift, its corners found again from a prediction a few pixels off, on every SIMD path alike.
#include "epipole/vision/window_matcher.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <set>
#include <vector>

#include "epipole/core/error.hpp"
#include "epipole/vision/fast.hpp"
#include "random_image.hpp"

namespace epipole::vision {
namespace {

constexpr int kW = 320, kH = 240;

// An image's described corners, kept (the matcher's spans last until its next call).
struct Described {
  std::vector<Corner> corners;
  SparseStereoMatcher matcher{{.width = kW, .height = kH, .max_disparity = 8}};
  DescribedCorners features;
  explicit Described(GrayView image) {
    FastDetector fast({.width = kW, .height = kH, .threshold = 20});
    const auto c = fast.detect(image);
    corners.assign(c.begin(), c.end());
    matcher.match(image, corners, image, corners);  // describes them
    features = matcher.left_features();
  }
};

GrayImage shifted(GrayView image, int dx, int dy) {
  GrayImage out(kW, kH);
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) {
      out.view()(x, y) = image(std::clamp(x - dx, 0, kW - 1), std::clamp(y - dy, 0, kH - 1));
    }
  }
  return out;
}

struct Queries {
  std::vector<std::uint8_t> descriptors;
  std::vector<float> x, y;
};

// The features of `from` as queries, expected at their place moved by (dx, dy).
Queries queries_of(const DescribedCorners& from, float dx, float dy) {
  Queries q;
  q.descriptors.assign(from.descriptors.begin(), from.descriptors.end());
  for (int i = 0; i < from.count(); ++i) {
    q.x.push_back(static_cast<float>(from.x[static_cast<std::size_t>(i)]) + dx);
    q.y.push_back(static_cast<float>(from.y[static_cast<std::size_t>(i)]) + dy);
  }
  return q;
}

TEST(WindowMatcher, FollowsFeaturesThatMovedTheSameOnEveryPath) {
  GrayImage a(kW, kH);
  test::fill(a.view(), test::Pattern::blobs, 5);
  const GrayImage b = shifted(a.view(), 11, -7);
  const Described from(a.view()), to(b.view());
  ASSERT_GT(from.features.count(), 100);
  const Queries q = queries_of(from.features, 11 + 3.4f, -7 - 2.6f);  // a prediction 4 px off
  std::vector<WindowMatch> reference;
  for (const SimdPath path : available_simd_paths()) {
    WindowMatcher matcher({.width = kW, .height = kH, .radius = 16}, path);
    const auto m = matcher.match(q.descriptors, q.x, q.y, to.features);
    // Features the shift took out of the image, or near its border, are not there.
    int inside = 0;
    for (int i = 0; i < from.features.count(); ++i) {
      const int x = from.features.x[static_cast<std::size_t>(i)] + 11;
      const int y = from.features.y[static_cast<std::size_t>(i)] - 7;
      inside += x >= 20 && x < kW - 20 && y >= 20 && y < kH - 20 ? 1 : 0;
    }
    int right = 0;
    std::set<int> corners;
    for (const WindowMatch& match : m) {
      const auto qi = static_cast<std::size_t>(match.query);
      const auto c = static_cast<std::size_t>(match.corner);
      const int x = from.features.x[qi] + 11, y = from.features.y[qi] - 7;
      right += to.features.x[c] == x && to.features.y[c] == y ? 1 : 0;
      EXPECT_TRUE(corners.insert(match.corner).second) << "a corner taken twice";
    }
    // Of the features still inside the moved image, most are found again.
    EXPECT_GT(static_cast<int>(m.size()), inside * 6 / 10) << to_string(path) << " " << inside;
    EXPECT_GE(right, static_cast<int>(m.size()) * 95 / 100) << to_string(path);
    if (path == SimdPath::reference) {
      reference.assign(m.begin(), m.end());
      continue;
    }
    ASSERT_EQ(m.size(), reference.size()) << to_string(path);
    for (std::size_t i = 0; i < m.size(); ++i) {
      EXPECT_EQ(m[i].query, reference[i].query);
      EXPECT_EQ(m[i].corner, reference[i].corner);
      EXPECT_EQ(m[i].distance, reference[i].distance);
    }
  }
}

// A prediction farther off than the window finds almost nothing, and nothing in the right place
// is claimed from the wrong one.
TEST(WindowMatcher, APredictionBeyondTheWindowFindsAlmostNothing) {
  GrayImage a(kW, kH);
  test::fill(a.view(), test::Pattern::blobs, 6);
  const GrayImage b = shifted(a.view(), 30, 0);
  const Described from(a.view()), to(b.view());
  const Queries q = queries_of(from.features, 0, 0);  // expected where they were
  WindowMatcher matcher({.width = kW, .height = kH, .radius = 8});
  const auto m = matcher.match(q.descriptors, q.x, q.y, to.features);
  EXPECT_LT(static_cast<int>(m.size()), from.features.count() / 10) << m.size();
}

TEST(WindowMatcher, BadInputIsAnError) {
  EXPECT_THROW(WindowMatcher({.width = kW, .height = kH, .radius = 0}), Error);
  EXPECT_THROW(WindowMatcher({.width = 0, .height = kH}), Error);
  EXPECT_THROW(WindowMatcher({.width = kW, .height = kH, .ratio = 0}), Error);
  GrayImage a(kW, kH);
  test::fill(a.view(), test::Pattern::blobs, 7);
  const Described from(a.view());
  Queries q = queries_of(from.features, 0, 0);
  WindowMatcher small({.width = kW, .height = kH, .max_queries = 4});
  EXPECT_THROW(small.match(q.descriptors, q.x, q.y, from.features), Error);
  WindowMatcher matcher({.width = kW, .height = kH});
  q.y.pop_back();
  EXPECT_THROW(matcher.match(q.descriptors, q.x, q.y, from.features), Error);
  // Queries off the image or not finite find nothing, without error.
  const std::vector<std::uint8_t> d(2 * SparseStereoMatcher::kDescriptorBytes, 0);
  const std::vector<float> x = {-5.0f, std::numeric_limits<float>::quiet_NaN()}, y = {10, 10};
  EXPECT_TRUE(matcher.match(d, x, y, from.features).empty());
}

}  // namespace
}  // namespace epipole::vision
