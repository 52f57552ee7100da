// The calibration's drift on the simulated board: scenes whose right camera turned after the
// calibration (board/sim's scenes with a `drift`), the offsets of the matches' rows to a
// fraction of a pixel and the turn estimated over the window; the smallest drift each figure
// sees (the whole-pixel rows of the stereo matches against the band's sub-pixel rows).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "board_scene.hpp"
#include "epipole/calib/health.hpp"
#include "epipole/core/angles.hpp"
#include "epipole/core/image_io.hpp"
#include "epipole/firmware/board_config.hpp"
#include "epipole/firmware/pipeline.hpp"
#include "epipole/firmware/rig_correction.hpp"
#include "epipole/vision/disparity_quality.hpp"
#include "maps_thread_wait.hpp"
#include "sim/sim_scene.hpp"
#include "sim/sim_settings.hpp"
#include "test_data.hpp"
#include "test_paths.hpp"

namespace epipole::firmware {
namespace {

struct DriftRun {
  calib::HealthFigure band;        // the last pair's sub-pixel figure
  calib::HealthFigure along_rows;  // the last pair's stereo matches, whole rows (the old figure)
  calib::DriftEstimate drift;      // over the window
};

// `pairs` pairs of board/sim's scene `name` (its pairs in turn), its right camera turned by
// `drift` ("" for none: a YAML map of sim.scenes.NAME.drift).
DriftRun run_drift(const std::string& name, const std::string& drift, int pairs) {
  std::vector<std::string> overrides;
  if (!drift.empty()) overrides.push_back("sim.scenes." + name + ".drift=" + drift);
  const test::BoardScene scene = test::board_scene(name, overrides);
  const BoardConfig& config = scene.config;
  const hal::StereoImages& images = scene.images;
  EXPECT_TRUE(scene.rig.has_value());
  Pipeline pipeline(config, scene.rig);
  calib::CalibrationHealth along(config.sparse.max_matches);
  std::vector<calib::RectifiedMatch> rows;
  DriftRun run;
  for (int i = 0; i < pairs; ++i) {
    const std::size_t k = static_cast<std::size_t>(i) % images.left.size();
    const FrameResult& r = pipeline.process(images.left[k].view(), images.right[k].view(),
                                            static_cast<std::uint32_t>(i), 0, config.stages);
    EXPECT_TRUE(r.calibration_health.has_value());
    EXPECT_TRUE(r.drift.has_value());
    if (!r.calibration_health || !r.drift) return run;
    run.band = *r.calibration_health;
    run.drift = *r.drift;
    rows.clear();
    for (const vision::SparseMatch& m : r.matches) rows.push_back({m.xl, m.yl, m.xr, m.yr});
    run.along_rows = along.measure(rows);
  }
  return run;
}

std::string drift_map(double pitch_deg, double roll_deg, double yaw_deg = 0) {
  char text[96];
  std::snprintf(text, sizeof text, "{pitch_deg: %g, roll_deg: %g, yaw_deg: %g}", pitch_deg,
                roll_deg, yaw_deg);
  return text;
}

// The drift: 0.3 degrees of pitch and 0.2 of roll on the faces' rig (f = 700 pixels): the
// rows about 3.7 pixels apart, the right way; the turn found within 0.02 degrees.
TEST(DriftScene, ATurnedCameraIsSeenTheRightWayAndMeasured) {
  if (!hal::can_load_scenes()) GTEST_SKIP() << "this build replays no image files";
  const DriftRun run = run_drift("faces", drift_map(0.3, 0.2), 6);
  EXPECT_GE(run.band.median_signed_px, 1.0);
  EXPECT_GT(run.band.matches, 100);
  ASSERT_TRUE(run.drift.valid);
  EXPECT_NEAR(degrees(run.drift.pitch), 0.3, 0.02);
  EXPECT_NEAR(degrees(run.drift.roll), 0.2, 0.02);
  EXPECT_LT(run.drift.median_corrected_px, 0.1);
  const DriftRun down = run_drift("faces", drift_map(-0.3, -0.2), 6);
  EXPECT_LE(down.band.median_signed_px, -1.0);
  EXPECT_NEAR(degrees(down.drift.pitch), -0.3, 0.02);
  EXPECT_NEAR(degrees(down.drift.roll), -0.2, 0.02);
}

TEST(DriftScene, AnUndriftedRigShowsNone) {
  if (!hal::can_load_scenes()) GTEST_SKIP() << "this build replays no image files";
  // Hundreds of pairs at 640x480: on the host (the kernels are tested bit-exact on ARM).
  if (EPIPOLE_UNDER_QEMU) GTEST_SKIP() << "left to the host: minutes under qemu";
  for (const std::string scene : {"faces", "aloe", "ground"}) {
    const DriftRun run = run_drift(scene, "", 4);
    SCOPED_TRACE(scene);
    std::printf("%s undrifted: median offset %.3f px, pitch %.4f roll %.4f deg\n", scene.c_str(),
                run.band.median_signed_px, degrees(run.drift.pitch), degrees(run.drift.roll));
    EXPECT_LT(std::abs(run.band.median_signed_px), 0.05);
    ASSERT_TRUE(run.drift.valid);
    EXPECT_LT(std::abs(degrees(run.drift.pitch)), 0.02);
    EXPECT_LT(std::abs(degrees(run.drift.roll)), 0.02);
  }
}

// Other scenes and turns: a real photograph pair (Aloe), and the rendered room seen through a
// real rig's distorting lenses (each pair its own sensor noise), yaw among the turns.
TEST(DriftScene, OtherScenesAndTurns) {
  if (!hal::can_load_scenes()) GTEST_SKIP() << "this build replays no image files";
  // Hundreds of pairs at 640x480: on the host (the kernels are tested bit-exact on ARM).
  if (EPIPOLE_UNDER_QEMU) GTEST_SKIP() << "left to the host: minutes under qemu";
  struct Case {
    std::string scene;
    double pitch, roll, yaw;
  };
  // Aloe's rig has f = 1617 pixels: its band of 8 rows sees turns up to about 0.28 degrees.
  for (const Case& c : {Case{"aloe", -0.2, 0.05, 0}, Case{"aloe", 0.05, -0.15, 0},
                        Case{"ground", 0.2, -0.3, 0.1}, Case{"ground", -0.7, 0.0, 0}}) {
    const DriftRun run = run_drift(c.scene, drift_map(c.pitch, c.roll, c.yaw), 8);
    SCOPED_TRACE(c.scene + " " + drift_map(c.pitch, c.roll, c.yaw));
    ASSERT_TRUE(run.drift.valid);
    EXPECT_NEAR(degrees(run.drift.pitch), c.pitch, 0.03);
    EXPECT_NEAR(degrees(run.drift.roll), c.roll, 0.03);
    std::printf(
        "%s %s: median offset %.3f px, estimate pitch %.4f (%.4f) roll %.4f (%.4f) deg, "
        "%d pairs %d matches, corrected %.3f px\n",
        c.scene.c_str(), drift_map(c.pitch, c.roll, c.yaw).c_str(), run.band.median_signed_px,
        degrees(run.drift.pitch), degrees(run.drift.pitch_sigma), degrees(run.drift.roll),
        degrees(run.drift.roll_sigma), run.drift.pairs, run.drift.matches,
        run.drift.median_corrected_px);
  }
}

// The smallest drift each figure sees: pitch turns worth 0.05 to 2 pixels of row offset on the
// faces' rig. The stereo matches' whole rows (the figure before the band) say 0 below half a
// pixel and lose the matches past the row tolerance; the band's sub-pixel rows follow the turn.
TEST(DriftScene, TheSmallestDriftEachFigureSees) {
  if (!hal::can_load_scenes()) GTEST_SKIP() << "this build replays no image files";
  // Hundreds of pairs at 640x480: on the host (the kernels are tested bit-exact on ARM).
  if (EPIPOLE_UNDER_QEMU) GTEST_SKIP() << "left to the host: minutes under qemu";
  std::printf("row offset | whole rows: median, matches | sub-pixel: median, matches | pitch\n");
  for (const double px : {0.05, 0.1, 0.2, 0.5, 1.0, 2.0}) {
    const double pitch_deg = degrees(std::atan(px / 700));
    const DriftRun run = run_drift("faces", drift_map(pitch_deg, 0), 3);
    std::printf("%.2f px | %.3f, %d | %.3f, %d | %.4f deg (%.4f)\n", px,
                run.along_rows.median_signed_px, run.along_rows.matches, run.band.median_signed_px,
                run.band.matches, degrees(run.drift.pitch), pitch_deg);
    EXPECT_NEAR(run.band.median_signed_px, px, 0.03 + 0.05 * px) << px << " px";
  }
}

// ----- Corrected while running

// Aloe's ground truth (samples/aloeGT.png, disparities in pixels) fitted as the scene fits its
// images (letterboxed), disparities scaled alike; 0 (unknown) outside.
Image<float> aloe_truth(int width, int height) {
  const GrayImage gt = load_gray(test::data_file("samples/aloeGT.png"));
  const hal::Letterbox box = hal::letterbox_geometry(gt.width(), gt.height(), width, height);
  Image<float> truth(width, height);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const int sx = static_cast<int>(std::floor((x - box.x + 0.5) / box.scale));
      const int sy = static_cast<int>(std::floor((y - box.y + 0.5) / box.scale));
      const bool inside = sx >= 0 && sy >= 0 && sx < gt.width() && sy < gt.height();
      truth(x, y) = inside ? static_cast<float>(gt(sx, sy) * box.scale) : 0.0f;
    }
  }
  return truth;
}

struct CorrectedRun {
  int corrections = 0;
  int started = 0;  // corrections the estimates started (consider() said so)
  calib::CameraTurn total;
  calib::HealthFigure last;
  calib::DriftEstimate drift;
  double median_depth_m = 0;  // of the last pair's 3-D points
  int points = 0;
  vision::DisparityQuality quality;  // of the last pair, against `truth` when given
  // The rectified cameras (P1, P2) and Q of the rig in use are the file's: what the outputs
  // published at start-up (camera_info, the depth's scale) stays true through corrections.
  bool rectified_cameras_kept = false;
};

// `pairs` pairs of scene `name`, its right camera turned by `drift` ("" none), the estimate
// considered after each pair as the frame loop does (online correction on when `online`).
CorrectedRun run_corrected(const std::string& name, const std::string& drift, int pairs,
                           bool online, std::vector<std::string> overrides = {},
                           const Image<float>* truth = nullptr, const GrayImage* mask = nullptr) {
  if (!drift.empty()) overrides.push_back("sim.scenes." + name + ".drift=" + drift);
  overrides.push_back(std::string("calibration_health.online_correction=") +
                      (online ? "true" : "false"));
  overrides.push_back("calibration_health.window_pairs=10");
  const test::BoardScene scene = test::board_scene(name, overrides);
  const BoardConfig& config = scene.config;
  const hal::StereoImages& images = scene.images;
  Pipeline pipeline(config, scene.rig);
  RigCorrection& correction = *pipeline.rig_correction();
  CorrectedRun run;
  for (int i = 0; i < pairs; ++i) {
    const std::size_t k = static_cast<std::size_t>(i) % images.left.size();
    const FrameResult& r = pipeline.process(images.left[k].view(), images.right[k].view(),
                                            static_cast<std::uint32_t>(i), 0, config.stages);
    if (r.drift && correction.consider(*r.drift) == RigCorrection::Outcome::started) ++run.started;
    EXPECT_TRUE(test::wait_for_maps_thread(correction));
    if (i + 1 < pairs) continue;
    run.last = r.calibration_health.value_or(calib::HealthFigure{});
    run.drift = r.drift.value_or(calib::DriftEstimate{});
    std::vector<double> depths;
    for (const SparsePoint& p : r.points) depths.push_back(p.z);
    run.points = static_cast<int>(depths.size());
    if (!depths.empty()) {
      std::nth_element(depths.begin(), depths.begin() + depths.size() / 2, depths.end());
      run.median_depth_m = depths[depths.size() / 2];
    }
    if (truth != nullptr) {
      run.quality = vision::disparity_quality(r.disparity, truth->view(), mask->view());
    }
  }
  run.corrections = correction.corrections();
  run.total = correction.total();
  const calib::StereoCalibration& in_use = correction.rig();
  run.rectified_cameras_kept = in_use.left.projection == scene.rig->left.projection &&
                               in_use.right.projection == scene.rig->right.projection &&
                               in_use.Q == scene.rig->Q;
  return run;
}

// The proof on the faces (everything at 2.625 m): with 0.3 degrees of pitch and 0.2 of
// roll, the rows are corrected to under 0.1 px and the 3-D points are back at their depth.
TEST(DriftCorrection, TheFacesRigIsCorrectedAndItsPointsAreBackAtTheirDepth) {
  if (!hal::can_load_scenes()) GTEST_SKIP() << "this build replays no image files";
  // Hundreds of pairs at 640x480: on the host (the kernels are tested bit-exact on ARM).
  if (EPIPOLE_UNDER_QEMU) GTEST_SKIP() << "left to the host: minutes under qemu";
  const double z = 700 * 0.12 / 32;
  const CorrectedRun drifted = run_corrected("faces", drift_map(0.3, 0.2), 40, false);
  EXPECT_EQ(drifted.corrections, 0) << "online correction is off by default";
  EXPECT_GE(drifted.last.median_signed_px, 1.0);
  const CorrectedRun corrected = run_corrected("faces", drift_map(0.3, 0.2), 40, true);
  EXPECT_GE(corrected.corrections, 1);
  EXPECT_NEAR(degrees(corrected.total.pitch), 0.3, 0.02);
  EXPECT_NEAR(degrees(corrected.total.roll), 0.2, 0.02);
  EXPECT_TRUE(corrected.rectified_cameras_kept) << "camera_info and Q as published";
  EXPECT_LT(std::abs(corrected.last.median_signed_px), 0.1);
  EXPECT_LT(corrected.last.p90_px, 0.3);
  ASSERT_GT(corrected.points, 20);
  EXPECT_NEAR(corrected.median_depth_m, z, 0.02 * z);
  std::printf(
      "faces drifted: %d points, median depth %.3f m, rows %.3f px; corrected (%d): %d "
      "points, %.3f m, rows %.3f px, turn %.4f, %.4f deg\n",
      drifted.points, drifted.median_depth_m, drifted.last.median_signed_px, corrected.corrections,
      corrected.points, corrected.median_depth_m, corrected.last.median_signed_px,
      degrees(corrected.total.pitch), degrees(corrected.total.roll));
}

// Undrifted rigs are never corrected, online correction on.
TEST(DriftCorrection, AnUndriftedRigsMapsNeverMove) {
  if (!hal::can_load_scenes()) GTEST_SKIP() << "this build replays no image files";
  // Hundreds of pairs at 640x480: on the host (the kernels are tested bit-exact on ARM).
  if (EPIPOLE_UNDER_QEMU) GTEST_SKIP() << "left to the host: minutes under qemu";
  for (const std::string scene : {"faces", "aloe", "ground"}) {
    SCOPED_TRACE(scene);
    const CorrectedRun run = run_corrected(scene, "", 24, true);
    EXPECT_EQ(run.corrections, 0);
    EXPECT_EQ(run.started, 0) << "not even one started and not yet in place";
  }
}

// Aloe (f = 1617 px: its band widened to 12 rows to see 0.3 degrees): bad2 against the data
// set's truth, corrected, within a point of the undrifted run's. Counted where both cameras
// still see the scene: the turned camera lost the top 9 rows (and a row more at the corners),
// which no correction brings back and which bad2 would count as missing.
TEST(DriftCorrection, AloesDepthIsBackWithinAPointOfBad2) {
  if (!hal::can_load_scenes()) GTEST_SKIP() << "this build replays no image files";
  // Hundreds of pairs at 640x480: on the host (the kernels are tested bit-exact on ARM).
  if (EPIPOLE_UNDER_QEMU) GTEST_SKIP() << "left to the host: minutes under qemu";
  const Image<float> truth = aloe_truth(640, 480);
  GrayImage shared(640, 480);
  for (int y = 0; y < 480; ++y) {
    for (int x = 0; x < 640; ++x) shared(x, y) = y >= 12 && y < 468 ? 1 : 0;
  }
  const std::vector<std::string> band{"calibration_health.band_rows=12"};
  const CorrectedRun undrifted = run_corrected("aloe", "", 3, false, band, &truth, &shared);
  const CorrectedRun drifted =
      run_corrected("aloe", drift_map(0.3, 0.2), 3, false, band, &truth, &shared);
  const CorrectedRun corrected =
      run_corrected("aloe", drift_map(0.3, 0.2), 40, true, band, &truth, &shared);
  std::printf(
      "aloe bad2: undrifted %.3f %%, drifted %.3f %%, corrected %.3f %% (%d corrections, "
      "rows %.3f px)\n",
      100 * undrifted.quality.bad2, 100 * drifted.quality.bad2, 100 * corrected.quality.bad2,
      corrected.corrections, corrected.last.median_signed_px);
  EXPECT_GT(drifted.quality.bad2, undrifted.quality.bad2 + 0.02) << "the drift costs depth";
  EXPECT_GE(corrected.corrections, 1);
  EXPECT_LT(std::abs(corrected.quality.bad2 - undrifted.quality.bad2), 0.01);
  EXPECT_LT(std::abs(corrected.last.median_signed_px), 0.1);
}

}  // namespace
}  // namespace epipole::firmware
