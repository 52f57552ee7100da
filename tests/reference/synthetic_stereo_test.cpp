// The synthetic scenes with exact ground truth (support/synthetic_stereo.hpp): the generator's
// own exactness, then the quality mode beside OpenCV's StereoSGBM on each scene, all pixels and
// non-occluded ones, checked against the stored figures (stereo_scoring.hpp).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <opencv2/core.hpp>
#include <string>

#include "stereo_scoring.hpp"
#include "synthetic_stereo.hpp"

namespace epipole::vision {
namespace {

using test::mat_of;
using test::synthetic_scene;
using test::SyntheticPair;

TEST(SyntheticStereo, AFrontoPlaneIsOneDisparityAndItsLeftBorderIsUnseen) {
  const SyntheticPair p = synthetic_scene("fronto", 640, 480);
  long occluded = 0;
  for (int y = 0; y < 480; ++y) {
    for (int x = 0; x < 640; ++x) {
      ASSERT_EQ(p.truth(x, y), 37.25f);
      // Points left of x = 37.25 fall outside the right view.
      ASSERT_EQ(p.nonoccluded(x, y), x < 38 ? 128 : 255) << x << "," << y;
      occluded += p.nonoccluded(x, y) == 128 ? 1 : 0;
    }
  }
  EXPECT_EQ(occluded, 38 * 480);
}

TEST(SyntheticStereo, BoxesHideTheWallBesideThemAndEveryVisiblePointLooksTheSame) {
  const SyntheticPair p = synthetic_scene("boxes", 640, 480);
  // Row 240 crosses the wall (16 px), the first box (x 96..224, 48 px) and the second (x
  // 288..416, 72 px): unseen are the border (16 px), the wall left of the first box hidden by
  // it (48 - 16 = 32 px) and the wall left of the second (72 - 16 = 56 px).
  int unseen = 0;
  for (int x = 0; x < 640; ++x) unseen += p.nonoccluded(x, 240) == 128 ? 1 : 0;
  EXPECT_EQ(unseen, 16 + 32 + 56);
  EXPECT_EQ(p.nonoccluded(63, 240), 255);
  EXPECT_EQ(p.nonoccluded(64, 240), 128);
  EXPECT_EQ(p.nonoccluded(95, 240), 128);
  EXPECT_EQ(p.truth(96, 240), 48.0f);
  // Integer disparities: a point seen in both views has the same value in both but for the
  // cameras' gain, offset and noise (right = 0.92 left + 6, each within 3 levels).
  long compared = 0;
  double sum = 0;
  for (int y = 0; y < 480; ++y) {
    for (int x = 0; x < 640; ++x) {
      if (p.nonoccluded(x, y) != 255) continue;
      const int d = static_cast<int>(p.truth(x, y));
      const double expected = 0.92 * p.left(x, y) + 6;
      const double difference = p.right(x - d, y) - expected;
      ASSERT_LE(std::abs(difference), 3 + 0.92 * 3 + 1) << x << "," << y;
      sum += difference;
      ++compared;
    }
  }
  EXPECT_GT(compared, 640 * 480 * 8 / 10);
  EXPECT_NEAR(sum / static_cast<double>(compared), 0.0, 0.2) << "the noise has no bias";
}

TEST(SyntheticStereo, TheSameSceneEveryTime) {
  const SyntheticPair a = synthetic_scene("thin", 320, 240);
  const SyntheticPair b = synthetic_scene("thin", 320, 240);
  for (int y = 0; y < 240; ++y) {
    for (int x = 0; x < 320; ++x) {
      ASSERT_EQ(a.left(x, y), b.left(x, y));
      ASSERT_EQ(a.right(x, y), b.right(x, y));
      ASSERT_EQ(a.truth(x, y), b.truth(x, y));
    }
  }
}

// A synthetic scene at 640x480 as OpenCV images, and the mask of its non-occluded pixels.
struct SceneMats {
  cv::Mat left, right, truth, nonoccluded;
};
SceneMats scene_mats(const std::string& name) {
  const SyntheticPair p = synthetic_scene(name, 640, 480);
  SceneMats m{mat_of(p.left), mat_of(p.right), mat_of(p.truth), {}};
  cv::compare(mat_of(p.nonoccluded), 255, m.nonoccluded, cv::CMP_EQ);
  return m;
}

// The quality mode and SGBM with one range (128, the simulated board's) on each scene: the
// figures of docs/vision.md, the baseline that they do not get worse, and the issue of depth
// quality's aim on every scene for the simulated board's configuration (SGM, 128 disparities,
// occlusions filled): at most 0.8x SGBM's bad2 with at least its density.
TEST(SyntheticStereo, QualityModeBesideSgbmOnEveryScene) {
  constexpr int kDisparities = 128;
  for (const std::string& name : test::synthetic_scene_names()) {
    const auto [left, right, truth, nonoccluded] = scene_mats(name);
    const cv::Mat sgm = ours(left, right, StereoMethod::sgm, kDisparities);
    const cv::Mat sgbm = opencv_sgbm(left, right, kDisparities);
    const Scores sgm_all = score(sgm, truth), sgm_noc = score(sgm, truth, nonoccluded);
    const Scores cv_all = score(sgbm, truth), cv_noc = score(sgbm, truth, nonoccluded);
    std::printf("%s 640x480, %d disparities:\n", name.c_str(), kDisparities);
    print("epipole sgm, all", sgm_all);
    print("OpenCV StereoSGBM, all", cv_all);
    print("epipole sgm, non-occluded", sgm_noc);
    print("OpenCV StereoSGBM, non-occl.", cv_noc);
    std::printf("  bad2 epipole / SGBM: all %.2f, non-occluded %.2f\n", sgm_all.bad2 / cv_all.bad2,
                sgm_noc.bad2 / cv_noc.bad2);
    EXPECT_GT(sgm_all.density, 0.5) << name;
    StereoConfig shipped;
    shipped.max_disparity = kDisparities;
    shipped.fill_occlusions = true;
    const Scores shipped_all = score(ours(left, right, shipped), truth);
    print("epipole sgm, occl. filled, all", shipped_all);
    EXPECT_LE(shipped_all.bad2, 0.8 * cv_all.bad2) << name;
    EXPECT_GE(shipped_all.density, cv_all.density) << name;
    // The hole filling (disparity_filters.hpp) at three lengths; 64 px against the baseline.
    for (int hole : {16, 64, 128}) {
      const cv::Mat f = ours(left, right, StereoMethod::sgm, kDisparities, 1, hole);
      const Scores all = score(f, truth);
      print("sgm, holes <= " + std::to_string(hole) + ", all", all);
      print("sgm, holes <= " + std::to_string(hole) + ", non-occl.", score(f, truth, nonoccluded));
      if (hole == 64) {
        check_baseline("synthetic-" + name + "-640x480-" + std::to_string(kDisparities),
                       "sgm-holes64", all);
      }
    }
    check_baseline("synthetic-" + name + "-640x480-" + std::to_string(kDisparities), "sgm",
                   sgm_all);
  }
}

// The occlusions filled from their background (StereoConfig::fill_occlusions): how many of the
// pixels filled are occluded in the truth, and how many of them are within 2 px of it.
TEST(SyntheticStereo, OcclusionsTakeTheirBackground) {
  for (const std::string& name : test::synthetic_scene_names()) {
    const auto [left, right, truth, nonoccluded] = scene_mats(name);
    StereoConfig config;
    config.max_disparity = 128;
    const cv::Mat off = ours(left, right, config);
    config.fill_occlusions = true;
    const cv::Mat on = ours(left, right, config);
    long filled = 0, filled_occluded = 0, filled_right = 0;
    for (int y = 0; y < 480; ++y) {
      for (int x = 0; x < 640; ++x) {
        const int before = off.at<std::int16_t>(y, x), after = on.at<std::int16_t>(y, x);
        if (before >= 0) {
          ASSERT_EQ(after, before) << name << ": only holes change (" << x << ", " << y << ")";
          continue;
        }
        if (after < 0) continue;
        ++filled;
        filled_occluded += nonoccluded.at<std::uint8_t>(y, x) == 0 ? 1 : 0;
        const double error = std::abs(after / 16.0 - static_cast<double>(truth.at<float>(y, x)));
        filled_right += error <= 2 ? 1 : 0;
      }
    }
    std::printf(
        "%s 640x480: %ld pixels filled, %.1f %% of them occluded, %.1f %% within 2 px\n",
        name.c_str(), filled,
        100.0 * static_cast<double>(filled_occluded) / static_cast<double>(std::max(filled, 1L)),
        100.0 * static_cast<double>(filled_right) / static_cast<double>(std::max(filled, 1L)));
    print("sgm, all", score(off, truth));
    print("sgm, occlusions filled, all", score(on, truth));
    print("sgm, non-occluded", score(off, truth, nonoccluded));
    print("sgm, occl. filled, non-occl.", score(on, truth, nonoccluded));
    // Where there is much to fill (the boxes' walls, the low-texture box's), the fills are
    // mostly right; elsewhere there is little.
    if (filled >= 1000) {
      EXPECT_GE(static_cast<double>(filled_right), 0.8 * static_cast<double>(filled)) << name;
    }
    if (name == "boxes") {
      EXPECT_GT(filled, 20000) << "the walls the boxes hide";
    }
    check_baseline("synthetic-" + name + "-640x480-128", "sgm-occlusions", score(on, truth));
  }
}

// The spatial filter (disparity_filters.hpp) at two weights, 2 passes, steps up to 2 px: the
// share of pixels more than 1 px off and the mean error, and nothing filled or removed (the
// same density).
TEST(SyntheticStereo, TheSpatialFilterSmoothsWithinSurfaces) {
  for (const std::string& name : test::synthetic_scene_names()) {
    const auto [left, right, truth, nonoccluded] = scene_mats(name);
    StereoConfig config;
    config.max_disparity = 128;
    const Scores off = score(ours(left, right, config), truth, nonoccluded);
    std::printf("%s 640x480, non-occluded pixels:\n", name.c_str());
    print("sgm", off);
    for (int percent : {50, 25}) {
      config.spatial_percent = percent;
      const cv::Mat filtered = ours(left, right, config);
      const Scores on = score(filtered, truth, nonoccluded);
      print("sgm, spatial " + std::to_string(percent) + " %", on);
      EXPECT_EQ(on.density, off.density) << name << ": the filter fills nothing, removes nothing";
      EXPECT_LE(on.bad1, off.bad1) << name << ": more pixels within 1 px of the truth, not fewer";
      if (percent == 50) {
        check_baseline("synthetic-" + name + "-640x480-128", "sgm-spatial50",
                       score(filtered, truth));
      }
    }
  }
}

// The confidence ranks the pixels: those it trusts more are right more often. For thresholds
// 1 (every valid pixel), 64, 128 and 192: the share of pixels kept and bad2 among them.
TEST(SyntheticStereo, TheConfidenceSaysWhichPixelsToTrust) {
  constexpr int kThresholds[] = {1, 64, 128, 192};
  for (const std::string& name : test::synthetic_scene_names()) {
    const SyntheticPair p = synthetic_scene(name, 640, 480);
    StereoConfig config;
    config.width = 640;
    config.height = 480;
    config.max_disparity = 128;
    config.confidence = true;
    StereoMatcher matcher(config);
    const ImageView<const std::int16_t> d = matcher.compute(p.left.view(), p.right.view());
    const cv::Mat disparity = mat_of(d);
    const cv::Mat confidence = mat_of(matcher.confidence());
    for (int y = 0; y < 480; ++y) {
      for (int x = 0; x < 640; ++x) {
        ASSERT_EQ(d.row(y)[x] < 0, matcher.confidence().row(y)[x] == 0)
            << name << ": a valid pixel has a confidence, an invalid one none (" << x << ", " << y
            << ")";
      }
    }
    const cv::Mat truth = mat_of(p.truth);
    std::printf("%s: confidence at least / pixels kept / bad2 among them\n", name.c_str());
    double bad2[std::size(kThresholds)];
    for (std::size_t i = 0; i < std::size(kThresholds); ++i) {
      cv::Mat kept;
      cv::compare(confidence, kThresholds[i], kept, cv::CMP_GE);
      bad2[i] = score(disparity, truth, kept).bad2;
      std::printf("  %3d  %5.1f %%  %5.1f %%\n", kThresholds[i],
                  100.0 * cv::countNonZero(kept) / static_cast<double>(kept.total()),
                  100 * bad2[i]);
    }
    EXPECT_LT(bad2[2], bad2[0]) << name;
  }
}

// The temporal filter on eight pairs of one scene that differ only in the cameras' noise: how
// many valid pixels change by more than 1 px from one pair to the next (flicker), and the last
// pair's figures, without the filter and with it (the new pair's weight 25 %, steps up to 2 px).
TEST(SyntheticStereo, TheTemporalFilterSteadiesTheDepthOfAStillScene) {
  constexpr int kPairs = 8;
  for (const char* name : {"slanted", "low-texture"}) {
    double flicker[2] = {0, 0};
    Scores last[2];
    for (int filtered = 0; filtered < 2; ++filtered) {
      StereoConfig config;
      config.width = 640;
      config.height = 480;
      config.max_disparity = 128;
      config.temporal_percent = filtered ? 25 : 0;
      StereoMatcher matcher(config);
      cv::Mat previous;
      long changed = 0, compared = 0;
      for (int i = 0; i < kPairs; ++i) {
        const SyntheticPair p = synthetic_scene(name, 640, 480, 100 + static_cast<unsigned>(i));
        const ImageView<const std::int16_t> d = matcher.compute(p.left.view(), p.right.view());
        const cv::Mat now = mat_of(d);
        if (!previous.empty()) {
          for (int y = 0; y < 480; ++y) {
            for (int x = 0; x < 640; ++x) {
              const int a = previous.at<std::int16_t>(y, x), b = now.at<std::int16_t>(y, x);
              if (a < 0 || b < 0) continue;
              ++compared;
              changed += std::abs(a - b) > kDisparityScale ? 1 : 0;
            }
          }
        }
        previous = now;
        if (i == kPairs - 1) last[filtered] = score(now, mat_of(p.truth));
      }
      flicker[filtered] = static_cast<double>(changed) / static_cast<double>(compared);
    }
    std::printf(
        "%s, %d pairs: valid pixels changing by more than 1 px between pairs %.2f %% "
        "unfiltered, %.2f %% filtered\n",
        name, kPairs, 100 * flicker[0], 100 * flicker[1]);
    print("  last pair, unfiltered", last[0]);
    print("  last pair, filtered", last[1]);
    EXPECT_LT(flicker[1], flicker[0]) << name;
  }
}

}  // namespace
}  // namespace epipole::vision
