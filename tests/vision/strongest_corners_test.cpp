// StrongestCorners against a brute-force selection: every offer sorted by "stronger" (higher
// score, then earlier in raster order), the first cell_capacity of each cell kept, in raster order.
#include "epipole/vision/strongest_corners.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "epipole/core/error.hpp"

namespace epipole::vision {
namespace {

struct Grid {
  int width, height, max_corners, columns, rows;
};

std::vector<Corner> brute_force(const Grid& g, const std::vector<Corner>& offers) {
  const int cells = g.columns * g.rows;
  const int capacity = g.max_corners / cells;
  std::vector<std::vector<Corner>> per_cell(static_cast<std::size_t>(cells));
  for (const Corner& c : offers) {
    const int cell = (c.y * g.rows / g.height) * g.columns + c.x * g.columns / g.width;
    per_cell[static_cast<std::size_t>(cell)].push_back(c);
  }
  std::vector<Corner> kept;
  for (auto& corners : per_cell) {
    std::stable_sort(corners.begin(), corners.end(), [](const Corner& a, const Corner& b) {
      if (a.score != b.score) return a.score > b.score;
      return a.y != b.y ? a.y < b.y : a.x < b.x;
    });
    const auto n = std::min<std::size_t>(corners.size(), static_cast<std::size_t>(capacity));
    kept.insert(kept.end(), corners.begin(), corners.begin() + static_cast<std::ptrdiff_t>(n));
  }
  std::sort(kept.begin(), kept.end(),
            [](const Corner& a, const Corner& b) { return a.y != b.y ? a.y < b.y : a.x < b.x; });
  return kept;
}

// Offers at distinct positions in raster order (as the detectors make them), scores drawn from
// `scores`.
std::vector<Corner> offers_for(const Grid& g, const std::vector<float>& scores, double density,
                               std::mt19937& rng) {
  std::bernoulli_distribution take(density);
  std::uniform_int_distribution<std::size_t> pick(0, scores.size() - 1);
  std::vector<Corner> offers;
  for (int y = 0; y < g.height; ++y) {
    for (int x = 0; x < g.width; ++x) {
      if (take(rng)) offers.push_back({x, y, scores[pick(rng)]});
    }
  }
  return offers;
}

void expect_bitwise_scores_equal(const std::vector<Corner>& want, std::span<const Corner> got) {
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t i = 0; i < want.size(); ++i) {
    ASSERT_EQ(got[i].x, want[i].x) << i;
    ASSERT_EQ(got[i].y, want[i].y) << i;
    // -0 comes back as +0; every other score exactly as offered.
    ASSERT_EQ(got[i].score, want[i].score) << i;
    if (want[i].score != 0.0f) {
      ASSERT_EQ(std::signbit(got[i].score), std::signbit(want[i].score)) << i;
    }
  }
}

TEST(StrongestCorners, KeepsWhatABruteForceSelectionKeeps) {
  std::mt19937 rng(7);
  std::vector<float> fast_like = {0, 1, 2, 3, 20, 21, 40, 254};  // many ties
  std::vector<float> any_float = {-0.0f,
                                  0.0f,
                                  -1.5f,
                                  -1e30f,
                                  std::numeric_limits<float>::denorm_min(),
                                  -std::numeric_limits<float>::denorm_min(),
                                  1e-3f,
                                  3.25f,
                                  7e20f,
                                  std::numeric_limits<float>::infinity(),
                                  -std::numeric_limits<float>::infinity()};
  std::uniform_real_distribution<float> wide(-1000.0f, 1000.0f);
  for (int i = 0; i < 40; ++i) any_float.push_back(wide(rng));

  const Grid grids[] = {{37, 23, 50, 1, 1},     {64, 48, 48, 4, 3}, {101, 77, 1000, 5, 2},
                        {640, 480, 2000, 4, 4}, {13, 11, 7, 3, 2},  {200, 100, 3, 1, 1}};
  for (const Grid& g : grids) {
    StrongestCorners strongest(g.width, g.height, g.max_corners, g.columns, g.rows);
    for (const std::vector<float>* scores : {&fast_like, &any_float}) {
      for (const double density : {0.01, 0.3, 1.0}) {
        SCOPED_TRACE(testing::Message()
                     << g.width << "x" << g.height << " grid " << g.columns << "x" << g.rows
                     << " max " << g.max_corners << " density " << density);
        const std::vector<Corner> offers = offers_for(g, *scores, density, rng);
        strongest.clear();
        for (const Corner& c : offers) strongest.offer(c);
        const std::vector<Corner> want = brute_force(g, offers);
        const bool dropped = want.size() < offers.size();
        expect_bitwise_scores_equal(want, strongest.finish());
        EXPECT_EQ(strongest.truncated(), dropped);
      }
    }
  }
}

TEST(StrongestCorners, EmptiesItsCellsAtFinish) {
  StrongestCorners strongest(10, 10, 4, 2, 2);
  strongest.offer({1, 1, 5.0f});
  strongest.offer({8, 8, 6.0f});
  EXPECT_EQ(strongest.finish().size(), 2u);
  strongest.clear();
  EXPECT_TRUE(strongest.finish().empty());
}

TEST(StrongestCorners, AFinishedFrameLeavesNoFloorBehind) {
  // A full cell's floor rises to its weakest kept corner; after finish(), weaker corners are kept
  // again, without a clear().
  StrongestCorners strongest(16, 16, 2);
  for (int x = 0; x < 8; ++x) strongest.offer({x, 0, 100.0f + static_cast<float>(x)});
  const std::span<const Corner> kept = strongest.finish();
  const std::vector<Corner> strong(kept.begin(), kept.end());
  EXPECT_EQ(strong, (std::vector<Corner>{{6, 0, 106.0f}, {7, 0, 107.0f}}));
  EXPECT_TRUE(strongest.truncated());
  strongest.offer({1, 5, 1.0f});
  strongest.offer({2, 5, 2.0f});
  const std::span<const Corner> weak = strongest.finish();
  ASSERT_EQ(weak.size(), 2u);
  EXPECT_EQ(weak[0], (Corner{1, 5, 1.0f}));
  EXPECT_EQ(weak[1], (Corner{2, 5, 2.0f}));
}

TEST(StrongestCorners, RefusesImagesItCannotNumber) {
  EXPECT_THROW(StrongestCorners(65536, 10, 10), Error);
  EXPECT_THROW(StrongestCorners(10, 65536, 10), Error);
  EXPECT_NO_THROW(StrongestCorners(65535, 2, 10));
}

}  // namespace
}  // namespace epipole::vision
