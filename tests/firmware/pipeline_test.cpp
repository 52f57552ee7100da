// The vision stages of one pair: with threads the cascade runs beside the other stages, and the
// results are those of one thread, to the bit (the disparity: that of the matcher alone at the
// same thread count, whose row stripes differ from one thread's near their borders,
// docs/vision.md).
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

TEST(Pipeline, TheCascadeBesideTheOtherStagesGivesWhatOneThreadGives) {
  test::SimRig rig(160, 120, 8);
  BoardConfig config = rig.parse("threads: {count: 1}\n");
  config.stages |= stage_bit(protocol::Stage::sparse);
  rig.add_cascade(config);
  const auto calibration = load_board_calibration(config);
  ASSERT_TRUE(calibration.has_value());
  BoardConfig two = config;
  two.threads.count = 2;
  Pipeline one_thread(config, calibration);
  Pipeline beside(two, calibration);
  const SceneImages images = rig.images(3);
  vision::StereoConfig stereo = two.stereo;
  stereo.width = rig.width;
  stereo.height = rig.height;
  stereo.threads = 2;
  vision::StereoMatcher matcher(stereo);
  const calib::Triangulator triangulator(calibration->Q, 1, 1);
  DetectionDepthEstimator depth(triangulator, stereo.max_disparity);
  int detections = 0;
  int with_depth = 0;
  for (int round = 0; round < 2; ++round) {
    for (std::size_t i = 0; i < images.left.size(); ++i) {
      const FrameResult& a = one_thread.process(images.left[i].view(), images.right[i].view(),
                                                static_cast<std::uint32_t>(i), 0, config.stages);
      const FrameResult& b = beside.process(images.left[i].view(), images.right[i].view(),
                                            static_cast<std::uint32_t>(i), 0, config.stages);
      SCOPED_TRACE(i);
      EXPECT_EQ(a.stages, b.stages);
      for (const protocol::Stage s :
           {protocol::Stage::rectify, protocol::Stage::corners, protocol::Stage::disparity,
            protocol::Stage::sparse, protocol::Stage::detect}) {
        EXPECT_TRUE(protocol::has_stage(b.stages, s)) << protocol::stage_info(s).name;
        EXPECT_GT(b.times[static_cast<std::size_t>(s)], 0) << protocol::stage_info(s).name;
      }
      EXPECT_TRUE(same(a.corners_left, b.corners_left));
      EXPECT_TRUE(same(a.corners_right, b.corners_right));
      EXPECT_TRUE(same(a.matches, b.matches));
      EXPECT_TRUE(same(a.points, b.points));
      EXPECT_TRUE(same(a.detections, b.detections));
      EXPECT_TRUE(same_image(matcher.compute(b.left, b.right), b.disparity));
      ASSERT_EQ(b.detection_depths.size(), b.detections.size());
      for (std::size_t k = 0; k < b.detections.size(); ++k) {
        const DetectionDepth want = depth.estimate(b.detections[k], b.disparity);
        EXPECT_EQ(b.detection_depths[k].valid, want.valid);
        EXPECT_EQ(b.detection_depths[k].disparity, want.disparity);
        EXPECT_EQ(b.detection_depths[k].depth, want.depth);
        with_depth += want.valid ? 1 : 0;
      }
      detections += static_cast<int>(b.detections.size());
    }
  }
  EXPECT_GT(detections, 0) << "the random cascade fires on the textured images";
  EXPECT_GT(with_depth, 0);
}

}  // namespace
}  // namespace epipole::firmware
