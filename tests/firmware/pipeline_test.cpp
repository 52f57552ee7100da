// The vision stages of one pair on one pool: with threads, every stage's tasks share the
// workers, and the results are those of one thread, to the bit (the disparity: that of the
// matcher alone at the same thread count, whose row stripes differ from one thread's near their
// borders, docs/vision.md).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <optional>
#include <span>
#include <utility>

#include "epipole/core/error.hpp"
#include "epipole/firmware/firmware.hpp"
#include "epipole/firmware/pipeline.hpp"
#include "sim_rig.hpp"

namespace epipole::firmware {
namespace {

// Element by element, to the bit: every field of these structs is 4 bytes (no padding).
template <typename T>
bool same(std::span<const T> a, std::span<const T> b) {
  static_assert(sizeof(T) % 4 == 0 && alignof(T) == 4);
  return a.size() == b.size() &&
         std::equal(a.begin(), a.end(), b.begin(),
                    [](const T& x, const T& y) { return std::memcmp(&x, &y, sizeof(T)) == 0; });
}

template <typename T>
bool same_image(ImageView<const T> a, ImageView<const T> b) {
  if (a.width() != b.width() || a.height() != b.height()) return false;
  for (int y = 0; y < a.height(); ++y) {
    if (!std::equal(a.row(y), a.row(y) + a.width(), b.row(y))) return false;
  }
  return true;
}

bool same_depths(std::span<const DetectionDepth> a, std::span<const DetectionDepth> b) {
  return a.size() == b.size() &&
         std::equal(a.begin(), a.end(), b.begin(), [](const auto& x, const auto& y) {
           return x.valid == y.valid && x.disparity == y.disparity && x.depth == y.depth;
         });
}

// The rig's board with every stage on (sparse matching too, and a random cascade).
BoardConfig every_stage(const test::SimRig& rig, int threads) {
  BoardConfig config = rig.parse(cat("threads: {count: ", threads, "}\n"));
  config.stages |= stage_bit(protocol::Stage::sparse);
  rig.add_cascade(config);
  return config;
}

// Two and three threads: the matcher on two and three stripes (its own documented difference
// near the stripe borders); everything else one thread's, and the depths those of the disparity.
TEST(Pipeline, StagesSharingThePoolGiveWhatOneThreadGives) {
  test::SimRig rig(160, 120, 8);
  const BoardConfig config = every_stage(rig, 1);
  const auto calibration = load_board_calibration(config);
  ASSERT_TRUE(calibration.has_value());
  BoardConfig two = config;
  two.threads.count = 2;
  BoardConfig three = config;
  three.threads.count = 3;
  Pipeline one_thread(config, calibration);
  Pipeline two_threads(two, calibration);
  Pipeline three_threads(three, calibration);
  vision::StereoConfig stereo = config.stereo;
  stereo.width = rig.width;
  stereo.height = rig.height;
  stereo.threads = 2;
  vision::StereoMatcher two_stripes(stereo);
  stereo.threads = 3;
  vision::StereoMatcher three_stripes(stereo);
  const calib::Triangulator triangulator(calibration->Q, 1, 1);
  DetectionDepthEstimator depth(triangulator, stereo.max_disparity);
  const hal::StereoImages images = rig.images(3);
  int detections = 0;
  int with_depth = 0;
  for (int round = 0; round < 2; ++round) {
    for (std::size_t i = 0; i < images.left.size(); ++i) {
      SCOPED_TRACE(i);
      const auto process = [&](Pipeline& p) -> const FrameResult& {
        return p.process(images.left[i].view(), images.right[i].view(),
                         static_cast<std::uint32_t>(i), 0, config.stages);
      };
      const FrameResult& a = process(one_thread);
      const FrameResult& b = process(two_threads);
      const FrameResult& c = process(three_threads);
      for (const FrameResult* r : {&b, &c}) {
        EXPECT_EQ(r->stages, a.stages);
        for (const protocol::Stage s :
             {protocol::Stage::rectify, protocol::Stage::corners, protocol::Stage::disparity,
              protocol::Stage::sparse, protocol::Stage::detect}) {
          EXPECT_TRUE(protocol::has_stage(r->stages, s)) << protocol::stage_info(s).name;
          EXPECT_GT(r->times[static_cast<std::size_t>(s)], 0) << protocol::stage_info(s).name;
        }
        EXPECT_TRUE(same(a.corners_left, r->corners_left));
        EXPECT_TRUE(same(a.corners_right, r->corners_right));
        EXPECT_TRUE(same(a.matches, r->matches));
        EXPECT_TRUE(same(a.points, r->points));
        EXPECT_TRUE(std::equal(a.best_points.begin(), a.best_points.end(), r->best_points.begin(),
                               r->best_points.end()));
        ASSERT_TRUE(a.calibration_health && r->calibration_health);
        EXPECT_EQ(a.calibration_health->matches, r->calibration_health->matches);
        EXPECT_EQ(a.calibration_health->median_px, r->calibration_health->median_px);
        EXPECT_TRUE(same(a.detections, r->detections));
      }
      EXPECT_TRUE(same_image(two_stripes.compute(b.left, b.right), b.disparity));
      EXPECT_TRUE(same_image(three_stripes.compute(c.left, c.right), c.disparity));
      for (const FrameResult* r : {&a, &b, &c}) {
        ASSERT_TRUE(r->obstacles != nullptr);
        ASSERT_EQ(r->detection_depths.size(), r->detections.size());
        for (std::size_t k = 0; k < r->detections.size(); ++k) {
          const DetectionDepth want = depth.estimate(r->detections[k], r->disparity);
          EXPECT_TRUE(same_depths({&want, 1}, {&r->detection_depths[k], 1}));
          with_depth += want.valid ? 1 : 0;
        }
      }
      detections += static_cast<int>(a.detections.size());
    }
  }
  EXPECT_GT(detections, 0) << "the random cascade fires on the textured images";
  EXPECT_GT(with_depth, 0);
}

// A NextPair that hands out the images it is told to, once.
class GivenNextPair final : public NextPair {
 public:
  void give(GrayView left, GrayView right, std::uint32_t frame) {
    images_ = Images{left, right, frame};
  }
  std::optional<Images> take() override {
    ++calls;
    return std::exchange(images_, std::nullopt);
  }
  int calls = 0;

 private:
  std::optional<Images> images_;
};

// The next pair rectified while the current one ends (the frame loop's pipelining across pairs)
// is the pair rectified when it is processed, to the bit, and every later stage's result with
// it. A pair taken ahead but not processed next (a fresher one came), one of another size, or
// one processed without rectification leaves nothing behind.
TEST(Pipeline, PairsRectifiedAheadGiveWhatPairByPairGives) {
  test::SimRig rig(160, 120, 8);
  const BoardConfig config = every_stage(rig, 2);
  const auto calibration = load_board_calibration(config);
  ASSERT_TRUE(calibration.has_value());
  Pipeline by_pair(config, calibration);
  Pipeline ahead(config, calibration);
  const hal::StereoImages images = rig.images(3);
  GivenNextPair next;
  const auto process = [&](Pipeline& p, std::size_t i, std::uint32_t frame, StageMask stages,
                           NextPair* n) -> const FrameResult& {
    return p.process(images.left[i].view(), images.right[i].view(), frame, 0, stages, n);
  };
  const StageMask all = config.stages;
  const auto expect_same = [&](std::size_t i, std::uint32_t frame, StageMask stages) {
    const FrameResult& a = process(by_pair, i, frame, stages, nullptr);
    const FrameResult& b = process(ahead, i, frame, stages, &next);
    EXPECT_EQ(a.stages, b.stages);
    EXPECT_TRUE(same_image(a.left, b.left));
    EXPECT_TRUE(same_image(a.right, b.right));
    EXPECT_TRUE(same(a.corners_left, b.corners_left));
    EXPECT_TRUE(same(a.corners_right, b.corners_right));
    EXPECT_TRUE(same(a.matches, b.matches));
    EXPECT_TRUE(same(a.points, b.points));
    EXPECT_TRUE(same_image(a.disparity, b.disparity));
    ASSERT_EQ(a.obstacles == nullptr, b.obstacles == nullptr);
    if (a.obstacles != nullptr) {
      EXPECT_EQ(*a.obstacles, *b.obstacles);
    }
    EXPECT_EQ(a.calibration_health.has_value(), b.calibration_health.has_value());
    EXPECT_TRUE(same(a.detections, b.detections));
    EXPECT_TRUE(same_depths(a.detection_depths, b.detection_depths));
    EXPECT_EQ(protocol::has_stage(b.stages, protocol::Stage::rectify),
              b.times[static_cast<std::size_t>(protocol::Stage::rectify)] > 0);
  };
  std::uint32_t frame = 0;
  for (int round = 0; round < 2; ++round) {
    for (std::size_t i = 0; i < images.left.size(); ++i, ++frame) {
      SCOPED_TRACE(frame);
      const std::size_t n = (i + 1) % images.left.size();
      next.give(images.left[n].view(), images.right[n].view(), frame + 1);
      expect_same(i, frame, all);
    }
  }
  EXPECT_EQ(next.calls, 6);
  EXPECT_EQ(ahead.pairs_rectified_ahead(), 6u);
  EXPECT_EQ(ahead.pairs_used_ahead(), 5u) << "the first pair was rectified when processed";

  // Pair 6 was taken ahead; pair 7 is, but pair 8 is processed instead.
  next.give(images.left[1].view(), images.right[1].view(), 7);
  expect_same(0, 6, all);
  expect_same(2, 8, all);
  EXPECT_EQ(ahead.pairs_used_ahead(), 6u);
  // The same buffers again but another frame: not the pair taken ahead.
  next.give(images.left[0].view(), images.right[0].view(), 10);
  expect_same(1, 9, all);
  expect_same(0, 11, all);
  EXPECT_EQ(ahead.pairs_used_ahead(), 6u);
  // A next pair of another size is not taken up; the current pair is not disturbed.
  const GrayImage small(80, 60);
  next.give(small.view(), small.view(), 13);
  expect_same(1, 12, all);
  EXPECT_EQ(ahead.pairs_rectified_ahead(), 8u);
  // A pair taken ahead and dropped (its buffers went back): the same buffers and number later
  // are another pair.
  next.give(images.left[2].view(), images.right[2].view(), 13);
  expect_same(1, 12, all);
  ahead.drop_pair_ahead();
  by_pair.drop_pair_ahead();
  expect_same(2, 13, all);
  EXPECT_EQ(ahead.pairs_rectified_ahead(), 9u);
  EXPECT_EQ(ahead.pairs_used_ahead(), 6u);
  // Rectification off for the pair taken ahead: the raw images go on.
  next.give(images.left[2].view(), images.right[2].view(), 15);
  expect_same(0, 14, all);
  expect_same(2, 15, all & ~stage_bit(protocol::Stage::rectify));
  EXPECT_EQ(ahead.pairs_used_ahead(), 6u);
  // Rectification off for the current pair: nothing is taken ahead.
  const int calls = next.calls;
  expect_same(2, 16, all & ~stage_bit(protocol::Stage::rectify));
  EXPECT_EQ(next.calls, calls);
}

// The rig's two pairs for the temporal filter (25 %): pair 0 one pixel nearer than pair 1,
// within the filter's largest step, so blended; the board's stages with and without disparity.
struct TemporalPairs {
  explicit TemporalPairs(const test::SimRig& rig) : images(rig.images(2)) {
    images.right[0] = hal::synthesize_right(images.left[0].view(), rig.disparity + 1);
  }
  static BoardConfig board(const test::SimRig& rig) {
    BoardConfig config = rig.parse();
    config.stereo.temporal_percent = 25;
    return config;
  }
  const FrameResult& process(Pipeline& p, std::size_t i, StageMask stages) const {
    return p.process(images.left[i].view(), images.right[i].view(), static_cast<std::uint32_t>(i),
                     0, stages);
  }
  static StageMask without_disparity(StageMask stages) {
    return stages & ~stage_bit(protocol::Stage::disparity);
  }
  hal::StereoImages images;
};

// The temporal filter blends each disparity with the pairs before; after a gap (the frame loop
// resets the history when a camera is lost; a pair without disparity is a gap by itself) the next
// pair's disparity is what a pipeline that never saw the pairs before gives.
TEST(Pipeline, TheTemporalFilterStartsAgainAfterAGap) {
  test::SimRig rig(160, 120, 8);
  const BoardConfig config = TemporalPairs::board(rig);
  const auto calibration = load_board_calibration(config);
  ASSERT_TRUE(calibration.has_value());
  const TemporalPairs pairs(rig);
  const StageMask all = config.stages;
  ASSERT_TRUE(protocol::has_stage(all, protocol::Stage::disparity));

  Pipeline fresh(config, calibration);
  const FrameResult& alone = pairs.process(fresh, 1, all);
  ASSERT_TRUE(protocol::has_stage(alone.stages, protocol::Stage::disparity));

  Pipeline p(config, calibration);
  pairs.process(p, 0, all);
  EXPECT_FALSE(same_image(pairs.process(p, 1, all).disparity, alone.disparity))
      << "pair 1 after pair 0 is blended with it";
  pairs.process(p, 0, all);
  p.reset_history();
  EXPECT_TRUE(same_image(pairs.process(p, 1, all).disparity, alone.disparity));
  pairs.process(p, 0, all);
  pairs.process(p, 0, TemporalPairs::without_disparity(all));
  EXPECT_TRUE(same_image(pairs.process(p, 1, all).disparity, alone.disparity));
}

// A pair without disparity is a gap even when it is refused before its tasks run (here by the
// detector: an image larger than the board's, taken unrectified without a calibration).
TEST(Pipeline, ARefusedPairWithoutDisparityIsAGapToo) {
  test::SimRig rig(160, 120, 8);
  BoardConfig config = TemporalPairs::board(rig);
  rig.add_cascade(config);
  const TemporalPairs pairs(rig);
  const StageMask all = config.stages;
  ASSERT_TRUE(protocol::has_stage(all, protocol::Stage::detect));

  Pipeline fresh(config, std::nullopt);
  const FrameResult& alone = pairs.process(fresh, 1, all);
  Pipeline p(config, std::nullopt);
  pairs.process(p, 0, all);
  const GrayImage big(2 * rig.width, 2 * rig.height);
  EXPECT_THROW(p.process(big.view(), big.view(), 7, 0, TemporalPairs::without_disparity(all)),
               Error);
  EXPECT_TRUE(same_image(pairs.process(p, 1, all).disparity, alone.disparity));
}

}  // namespace
}  // namespace epipole::firmware
