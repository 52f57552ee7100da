// The vision stages of one pair on one pool: with threads, every stage's tasks share the
// workers, and the results are those of one thread, to the bit (the disparity: that of the
// matcher alone at the same thread count, whose row stripes differ from one thread's near their
// borders, docs/vision.md).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <span>

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

bool same_image(ImageView<const std::int16_t> a, ImageView<const std::int16_t> b) {
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

// Two and three threads: the matcher on two and three stripes (its own documented difference
// near the stripe borders); everything else one thread's, and the depths those of the disparity.
TEST(Pipeline, StagesSharingThePoolGiveWhatOneThreadGives) {
  test::SimRig rig(160, 120, 8);
  BoardConfig config = rig.parse("threads: {count: 1}\n");
  config.stages |= stage_bit(protocol::Stage::sparse);
  rig.add_cascade(config);
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
  const SceneImages images = rig.images(3);
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

// The temporal filter blends each disparity with the pairs before; after a gap (the frame loop
// resets the history when a camera is lost; a pair without disparity is a gap by itself) the next
// pair's disparity is what a pipeline that never saw the pairs before gives.
TEST(Pipeline, TheTemporalFilterStartsAgainAfterAGap) {
  test::SimRig rig(160, 120, 8);
  BoardConfig config = rig.parse();
  config.stereo.temporal_percent = 25;
  const auto calibration = load_board_calibration(config);
  ASSERT_TRUE(calibration.has_value());
  // Pair 0 one pixel nearer than pair 1: within the filter's largest step, so blended.
  SceneImages images = rig.images(2);
  images.right[0] = hal::synthesize_right(images.left[0].view(), rig.disparity + 1);
  const auto process = [&](Pipeline& p, std::size_t i, StageMask stages) -> const FrameResult& {
    return p.process(images.left[i].view(), images.right[i].view(), static_cast<std::uint32_t>(i),
                     0, stages);
  };
  const StageMask all = config.stages;
  const StageMask no_disparity = all & ~stage_bit(protocol::Stage::disparity);
  ASSERT_TRUE(protocol::has_stage(all, protocol::Stage::disparity));

  Pipeline fresh(config, calibration);
  const FrameResult& alone = process(fresh, 1, all);
  ASSERT_TRUE(protocol::has_stage(alone.stages, protocol::Stage::disparity));

  Pipeline p(config, calibration);
  process(p, 0, all);
  EXPECT_FALSE(same_image(process(p, 1, all).disparity, alone.disparity))
      << "pair 1 after pair 0 is blended with it";
  process(p, 0, all);
  p.reset_history();
  EXPECT_TRUE(same_image(process(p, 1, all).disparity, alone.disparity));
  process(p, 0, all);
  process(p, 0, no_disparity);
  EXPECT_TRUE(same_image(process(p, 1, all).disparity, alone.disparity));
}

}  // namespace
}  // namespace epipole::firmware
