// The calibration's drift on the simulated board: scenes whose right camera turned after the
// calibration (board/sim's scenes with a `drift`), the offsets of the matches' rows to a
// fraction of a pixel and the turn estimated over the window; the smallest drift each figure
// sees (the whole-pixel rows of the stereo matches against the band's sub-pixel rows).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "epipole/calib/health.hpp"
#include "epipole/core/angles.hpp"
#include "epipole/firmware/board_config.hpp"
#include "epipole/firmware/pipeline.hpp"
#include "sim/sim_settings.hpp"
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
  const hal::BackendOption option{"scene", name};
  std::vector<std::string> overrides;
  if (!drift.empty()) overrides.push_back("sim.scenes." + name + ".drift=" + drift);
  const BoardConfig config =
      load_board_config(std::filesystem::path(test::source_dir()) / "board" / "sim", overrides,
                        std::span(&option, 1));
  const std::optional<calib::StereoCalibration> rig = load_board_calibration(config);
  EXPECT_TRUE(rig.has_value());
  const hal::StereoImages images =
      hal::load_scene(hal::sim_settings(config.sections).chosen(), config.width(), config.height());
  Pipeline pipeline(config, rig);
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

}  // namespace
}  // namespace epipole::firmware
