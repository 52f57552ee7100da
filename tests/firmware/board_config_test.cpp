// The board file: every key read, every bad value an error naming the file and the key.
#include <gtest/gtest.h>
#include <sched.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include "epipole/calib/calibration.hpp"
#include "epipole/core/error.hpp"
#include "epipole/core/thread_pool.hpp"
#include "epipole/firmware/board_config.hpp"
#include "epipole/firmware/firmware.hpp"
#include "error_of.hpp"
#include "sim_rig.hpp"
#include "test_data.hpp"
#include "test_paths.hpp"

namespace epipole::firmware {
namespace {

using test::SimRig;

// The error message of parsing `text` as the board file, or "" when it parses.
std::string error_of(const SimRig& rig, const std::string& text) {
  try {
    parse_board_config(text, rig.dir.path() / "board.yaml");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(BoardConfig, ReadsEveryKey) {
  SimRig rig;
  const BoardConfig c = rig.parse(
      "pairing: {tolerance_us: 1500}\n"
      "obstacles: {sectors: 36, band: [0.1, 0.9], min_depth_m: 0.5, max_depth_m: 12, "
      "min_confidence: 96}\n"
      "depth_grid: {columns: 16, rows: 12, min_depth_m: 0.3, max_depth_m: 8, min_confidence: 64}\n"
      "threads: {count: 3, affinity: [0, 1], realtime_priority: 10, lock_memory: true}\n"
      "detector: {cascade: face.bin, scale_factor: 1.2, min_neighbors: 4, min_size: 40}\n"
      "memory_budget_mb: 8\n"
      "snapshot_directory: snaps\n"
      "snapshot_limit: 12\n"
      "snapshot_min_free_mb: 500\n");
  EXPECT_EQ(c.name, "test-sim");
  EXPECT_EQ(c.width(), 160);
  EXPECT_EQ(c.height(), 96);
  EXPECT_EQ(c.cameras.backend, "sim");
  EXPECT_EQ(c.cameras.left.device, "left");
  EXPECT_EQ(c.cameras.right.device, "right");
  EXPECT_EQ(c.cameras.left.trigger, hal::TriggerMode::external);
  EXPECT_EQ(c.cameras.timeout, 100'000'000);
  EXPECT_EQ(c.trigger.line.rate_hz, 30.0);
  EXPECT_EQ(c.pairing.tolerance, 1'500'000);
  EXPECT_EQ(c.pairing.trigger_period, 33'333'333);
  EXPECT_EQ(c.serial.backend, "none");
  EXPECT_EQ(c.calibration, rig.dir.path() / "rig.yaml");
  EXPECT_EQ(c.stereo.max_disparity, 32);
  EXPECT_FALSE(protocol::has_stage(c.stages, protocol::Stage::sparse));
  EXPECT_TRUE(protocol::has_stage(c.stages, protocol::Stage::disparity));
  EXPECT_EQ(c.obstacles.sectors, 36);
  EXPECT_EQ(c.obstacles.band_top, 0.1);
  EXPECT_EQ(c.obstacles.max_depth_m, 12.0);
  EXPECT_EQ(c.obstacles.min_confidence, 96);
  EXPECT_EQ(c.depth_grid.columns, 16);
  EXPECT_EQ(c.depth_grid.rows, 12);
  EXPECT_EQ(c.depth_grid.min_depth_m, 0.3);
  EXPECT_EQ(c.depth_grid.max_depth_m, 8.0);
  EXPECT_EQ(c.depth_grid.min_confidence, 64);
  EXPECT_EQ(c.threads.count, 3);
  EXPECT_EQ(c.threads.affinity, (std::vector<int>{0, 1}));
  EXPECT_EQ(c.threads.realtime_priority, 10);
  EXPECT_TRUE(c.threads.lock_memory);
  EXPECT_EQ(c.detector.cascade, rig.dir.path() / "face.bin");
  EXPECT_EQ(c.detector.min_neighbors, 4);
  EXPECT_EQ(*c.memory_budget_bytes, 8u * 1024 * 1024);
  EXPECT_EQ(c.snapshot_directory, rig.dir.path() / "snaps");
  EXPECT_EQ(c.snapshot_limit, 12);
  EXPECT_EQ(c.snapshot_min_free_mb, 500.0);
  EXPECT_EQ(test::sim(c).chosen().synthesize_disparity, 8);
}

// Without threads.count the vision stages get the CPUs the firmware may run on: those of
// threads.affinity, else the process's (a service manager's CPUAffinity narrows them).
TEST(BoardConfig, ThreadsDefaultToTheUsableCpus) {
  SimRig rig;
  EXPECT_EQ(rig.parse("threads: {lock_memory: false}\n").threads.count, usable_cpus());
  EXPECT_EQ(rig.parse("threads: {affinity: [0]}\n").threads.count, 1);
  EXPECT_EQ(rig.parse("threads: {affinity: [0, 1, 2]}\n").threads.count, 3);
  EXPECT_EQ(rig.parse("threads: {affinity: [1, 1]}\n").threads.count, 1) << "CPUs, not entries";
  EXPECT_EQ(rig.parse("threads: {count: 1, affinity: [0, 1]}\n").threads.count, 1);
  cpu_set_t set;
  CPU_ZERO(&set);
  ASSERT_EQ(sched_getaffinity(0, sizeof set, &set), 0);
  EXPECT_EQ(usable_cpus(), CPU_COUNT(&set));
}

TEST(BoardConfig, ExpandsEnvironmentVariablesInPaths) {
  SimRig rig;
  ::setenv("EPIPOLE_TEST_FOLDER", "/some/where", 1);
  const BoardConfig c = rig.parse("snapshot_directory: ${EPIPOLE_TEST_FOLDER}/snaps\n");
  EXPECT_EQ(c.snapshot_directory, "/some/where/snaps");
  ::unsetenv("EPIPOLE_TEST_FOLDER");
  EXPECT_NE(error_of(rig, rig.yaml("snapshot_directory: ${EPIPOLE_TEST_FOLDER}/snaps\n"))
                .find("environment variable EPIPOLE_TEST_FOLDER is not set"),
            std::string::npos);
}

struct BadCase {
  const char* what;
  std::string from;  // replaced in the rig's file ...
  std::string to;    // ... by this (or appended when `from` is empty)
  const char* expected;
};

TEST(BoardConfig, EveryBadValueNamesTheFileAndTheKey) {
  SimRig rig;
  const BadCase cases[] = {
      {"unknown key", "", "colour: blue\n", "unknown key 'colour'"},
      {"newer version", "version: 1", "version: 2", "version: 2 is not a board file version"},
      {"no size", ", width: 160", "", "missing key 'cameras.width'"},
      {"bad format", "trigger: external,", "trigger: external, format: rgb24,",
       "cameras.format: 'rgb24' is not one of"},
      {"bad trigger mode", "trigger: external", "trigger: sometimes",
       "cameras.trigger: 'sometimes' is not one of free_running, external"},
      {"unknown backend", "backend: sim, left", "backend: gige, left",
       "cameras.backend: 'gige' is not one of sim, v4l2, libcamera"},
      {"unknown trigger backend", "trigger: {backend: sim", "trigger: {backend: gpio",
       "trigger.backend: 'gpio' is not one of sim, gpiod, none"},
      {"unknown serial backend", "serial: {backend: none}", "serial: {backend: uart}",
       "serial.backend: 'uart' is not one of termios, pty, none"},
      {"impossible rate", "rate_hz: 30", "rate_hz: -5", "trigger.rate_hz: -5 is outside"},
      {"disparity not /16", "max_disparity: 32", "max_disparity: 40",
       "stereo.max_disparity: 40 is not a multiple of 16"},
      {"disparity too wide", "max_disparity: 32", "max_disparity: 256",
       "stereo.max_disparity: 256 is not smaller than the width 160"},
      {"tolerance", "", "pairing: {tolerance_us: 20000}\n",
       "pairing.tolerance_us: 20000 us is not below half the trigger period"},
      {"a rate the cameras' timeout cannot follow", "rate_hz: 30", "rate_hz: 5",
       "trigger.rate_hz: a frame every 200 ms does not come within the cameras' timeout of 100 "
       "ms"},
      {"an exposure longer than the period", "trigger: external",
       "trigger: external, exposure_us: 40000",
       "trigger.rate_hz: an exposure of 40 ms does not fit in the frame period of 33.3333 ms"},
      {"snapshot limit", "", "snapshot_limit: 0\n", "snapshot_limit: 0 is outside 1..1000000"},
      {"termios without device", "serial: {backend: none}", "serial: {backend: termios}",
       "serial.device: a termios serial port needs a device"},
      {"bad baud", "serial: {backend: none}",
       "serial: {backend: termios, device: /dev/ttyS0, baud: 12345}",
       "serial.baud: 12345 is not a baud rate termios supports"},
      {"a baud rate that cannot carry the summaries", "serial: {backend: none}",
       "serial: {backend: pty, baud: 9600}",
       "serial.baud: 9600 baud carries 960 bytes/s, but the pair summaries and health alone "
       "need"},
      {"nor MAVLink's obstacle distances", "serial: {backend: none}",
       "serial: {backend: pty, baud: 19200, protocol: mavlink}",
       "serial.baud: 19200 baud carries 1920 bytes/s, but the obstacle distances"},
      {"bad protocol", "serial: {backend: none}", "serial: {backend: none, protocol: nmea}",
       "serial.protocol: 'nmea' is not one of epipole, mavlink"},
      {"unknown scene", "",
       "sim: {scene: nowhere, scenes: {a: {synthesize: x.png, disparity: 1}}}\n",
       "sim.scene: 'nowhere' is not a scene of this board (a)"},
      {"a simulated board without its section",
       "sim: {charge_compute: false, scenes: {test: {synthesize: unused.png, disparity: 8}}}\n", "",
       "sim.scenes: the simulated board needs at least one scene"},
      {"glob without files", "synthesize: unused.png, disparity: 8",
       "left: nothing-here-*.png, right: nothing-there-*.png",
       "sim.scenes.test.left: no file matches"},
      {"confidence", "", "obstacles: {min_confidence: 300}\n",
       "obstacles.min_confidence: 300 is outside"},
      {"band", "", "obstacles: {band: [0.8, 0.2]}\n",
       "obstacles.band: expected [top, bottom] with 0 <= top < bottom <= 1"},
      {"sector range", "", "obstacles: {max_depth_m: 100}\n",
       "obstacles.max_depth_m: 100 is outside"},
      {"grid half off", "", "depth_grid: {columns: 8}\n",
       "depth_grid: columns and rows are both 0 (no grid) or both at least 1"},
      {"grid too big", "", "depth_grid: {columns: 16, rows: 16}\n",
       "depth_grid: 16x16 cells is more than the 240 a message holds"},
      {"grid range", "", "depth_grid: {columns: 4, rows: 3, min_depth_m: 5, max_depth_m: 2}\n",
       "depth_grid.max_depth_m: must be greater than min_depth_m"},
      {"ground heights", "", "ground: {height_m: [2, 1]}\n",
       "ground.height_m: must be [lowest, highest] metres"},
      {"ground heights, one", "", "ground: {height_m: [1]}\n",
       "ground.height_m: must be [lowest, highest] metres"},
      {"ground pitch", "", "ground: {max_pitch_deg: 85}\n", "ground.max_pitch_deg: 85 is outside"},
      {"ground iterations", "", "ground: {iterations: 0}\n", "ground.iterations: 0 is outside"},
      {"ground key", "", "ground: {clearance: 0.2}\n", "unknown key 'ground.clearance'"},
      {"affinity", "", "threads: {affinity: [0.5]}\n", "threads.affinity: 0.5 is not a CPU number"},
      {"boolean", "sparse: false", "sparse: maybe", "stages.sparse: expected true or false"},
      {"an always-on stage", "sparse: false", "sparse: false, publish: false",
       "unknown key 'stages.publish'"},
      {"not a map", "", "stereo: 12\n", "stereo: expected a map of keys"},
      {"malformed", "", "cameras: [\n", "malformed YAML"},
      {"a key twice", "stages: {", "stereo: {max_disparity: 16}\nstages: {",
       "line 9: key 'stereo' appears twice"},
      {"a key twice in a map", "max_disparity: 32}", "max_disparity: 32, max_disparity: 16}",
       "line 7: key 'stereo.max_disparity' appears twice"},
  };
  // The rig's file (yaml()) has one `sim:` and `stereo:` key; cases that add their own drop
  // the rig's first.
  for (const BadCase& c : cases) {
    std::string text = rig.yaml();
    if (c.from.empty()) {
      for (const char* key : {"sim:", "stereo:", "obstacles:", "threads:", "pairing:"}) {
        if (c.to.rfind(key, 0) != 0) continue;
        const std::size_t at = text.find(std::string("\n") + key);
        if (at != std::string::npos) text.erase(at + 1, text.find('\n', at + 1) - at);
      }
      text += c.to;
    } else {
      const std::size_t at = text.find(c.from);
      ASSERT_NE(at, std::string::npos) << c.what;
      text.replace(at, c.from.size(), c.to);
    }
    const std::string error = error_of(rig, text);
    EXPECT_NE(error.find(c.expected), std::string::npos) << c.what << ": got '" << error << "'";
    EXPECT_NE(error.find("board.yaml"), std::string::npos) << c.what << ": " << error;
  }
}

// epipole-fw --scene: an option for the section of the cameras' backend, which checks it; a
// backend without a section takes none.
TEST(BoardConfig, CameraOptionsGoToTheCamerasBackendSection) {
  SimRig rig;
  const std::string text =
      rig.yaml("").replace(rig.yaml("").find("scenes: {"), 9,
                           "scenes: {other: {synthesize: unused.png, disparity: 4}, ");
  const std::filesystem::path file = rig.dir.path() / "board.yaml";
  EXPECT_EQ(test::sim(parse_board_config(text, file)).scene, "other") << "the file's first";
  const std::vector<hal::BackendOption> scene = {{"scene", "test"}};
  EXPECT_EQ(test::sim(parse_board_config(text, file, scene)).chosen().synthesize_disparity, 8);

  const std::vector<hal::BackendOption> nowhere = {{"scene", "nowhere"}};
  EXPECT_NE(test::error_of([&] {
              parse_board_config(text, file, nowhere);
            }).find("board.yaml: sim.scene: 'nowhere' is not a scene of this board (other, test)"),
            std::string::npos);
  const std::vector<hal::BackendOption> colour = {{"colour", "blue"}};
  EXPECT_NE(test::error_of([&] {
              parse_board_config(text, file, colour);
            }).find("the simulated board takes no option 'colour'"),
            std::string::npos);

  std::string v4l2 = rig.yaml();
  v4l2.replace(v4l2.find("backend: sim, left: left, right: right"), 38,
               "backend: v4l2, left: /dev/video0, right: /dev/video2");
  v4l2.replace(v4l2.find("trigger: {backend: sim"), 22, "trigger: {backend: none");
  v4l2.replace(v4l2.find("trigger: external"), 17, "trigger: free_running");
  EXPECT_TRUE(parse_board_config(v4l2, file).sections.find("sim") != nullptr)
      << "a section the file has is read, used or not";
  EXPECT_NE(test::error_of([&] {
              parse_board_config(v4l2, file, scene);
            }).find("cameras.backend: 'v4l2' takes no option 'scene'"),
            std::string::npos);
  std::string unknown = v4l2;
  unknown.replace(unknown.find("backend: v4l2"), 13, "backend: gige");
  EXPECT_NE(test::error_of([&] {
              parse_board_config(unknown, file, scene);
            }).find("cameras.backend: 'gige' is not one of sim, v4l2, libcamera"),
            std::string::npos)
      << "an unknown backend is said as such, options or not";
}

TEST(BoardConfig, AFolderMeansItsBoardFile) {
  SimRig rig;
  std::ofstream(rig.dir.path() / "board.yaml") << rig.yaml();
  EXPECT_EQ(load_board_config(rig.dir.path()).name, "test-sim");
  try {
    load_board_config(rig.dir.path() / "missing");
    FAIL() << "a missing board file must be an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("missing"), std::string::npos) << e.what();
  }
}

// `epipole-bench --set KEY=VALUE`: keys set over the file's, nested or new, validated as the
// file is; an override that cannot apply is an error naming it.
TEST(BoardConfig, OverridesSetKeysBeforeTheFileIsRead) {
  SimRig rig;
  std::ofstream(rig.dir.path() / "board.yaml") << rig.yaml();
  const std::vector<std::string> overrides{
      "stereo.method=bm",           "corners.threshold=35",      "sparse.max_points=7",
      "obstacles.band=[0.2, 0.6]",  "stereo.spatial_percent=40", "stereo.spatial_passes=3",
      "stereo.fill_occlusions=true"};
  const BoardConfig c = load_board_config(rig.dir.path(), overrides);
  EXPECT_EQ(c.stereo.method, vision::StereoMethod::bm);
  EXPECT_EQ(c.stereo.max_disparity, 32) << "the other keys of the map stay";
  EXPECT_EQ(c.corners.threshold, 35);
  EXPECT_EQ(c.corners.max_corners, 500);
  EXPECT_EQ(c.sparse.max_points, 7) << "a map the file does not have is added";
  EXPECT_EQ(c.stereo.spatial_percent, 40);
  EXPECT_TRUE(c.stereo.fill_occlusions);
  EXPECT_EQ(c.stereo.spatial_passes, 3);
  EXPECT_EQ(c.stereo.spatial_max_step, 2) << "the default";
  EXPECT_DOUBLE_EQ(c.obstacles.band_top, 0.2);
  EXPECT_DOUBLE_EQ(c.obstacles.band_bottom, 0.6);
  EXPECT_EQ(load_board_config(rig.dir.path(), {}).stereo.method, vision::StereoMethod::sgm);

  const struct {
    std::string override_text;
    const char* expected;
  } bad[] = {
      {"stereo.method", "is not KEY=VALUE"},
      {"=bm", "is not KEY=VALUE"},
      {"stereo..method=bm", "empty key"},
      {"stereo.method.=bm", "empty key"},
      {"version.x=1", "inside version, which is not a map"},
      {"corners.threshold=[1, 2", "not YAML"},
      {"stereo.method=fast", "stereo.method"},
      {"stereo.colour=red", "colour"},
      {"stereo.spatial_passes=5", "stereo.spatial_passes: 5 is outside"},
      {"stereo.spatial_percent=100", "stereo.spatial_percent: 100 is outside"},
      {"stereo.fill_occlusions=maybe", "stereo.fill_occlusions"},
  };
  for (const auto& b : bad) {
    const std::vector<std::string> one{b.override_text};
    const std::string error = test::error_of([&] { load_board_config(rig.dir.path(), one); });
    EXPECT_NE(error.find(b.expected), std::string::npos)
        << b.override_text << ": got '" << error << "'";
    EXPECT_NE(error.find("board.yaml"), std::string::npos) << b.override_text << ": " << error;
  }
}

// Every board file the repository ships (board/*/board.yaml and board/*/board-*.yaml: what a
// user copies to start a board of their own) loads through the firmware's own reading and
// validation, and so does every calibration file it names that ships beside it.
TEST(BoardConfig, EveryShippedBoardLoads) {
  namespace fs = std::filesystem;
  // The simulated boards name the fetched data sets: the same folder for the test and the board.
  const fs::path data = test::data_file("samples/left01.jpg").parent_path().parent_path();
  ::setenv("EPIPOLE_DATA_DIR", data.c_str(), 1);
  std::vector<std::string> loaded;
  for (const auto& folder : fs::directory_iterator(fs::path(test::source_dir()) / "board")) {
    if (!folder.is_directory()) continue;
    EXPECT_TRUE(fs::exists(folder.path() / "board.yaml")) << folder.path() << ": no board.yaml";
    for (const auto& entry : fs::directory_iterator(folder.path())) {
      const std::string name = entry.path().filename().string();
      if (name != "board.yaml" && !(name.starts_with("board-") && name.ends_with(".yaml"))) {
        continue;
      }
      BoardConfig c;
      const std::string error = test::error_of([&] { c = load_board_config(entry.path()); });
      EXPECT_EQ(error, "") << entry.path();
      if (!error.empty()) continue;
      loaded.push_back(folder.path().filename().string() + "/" + name);
      // A board's own rig.yaml is made by epipole calibrate on the user's rig; a file that
      // ships in the repository must load.
      const bool simulated =
          hal::BackendRegistry::builtin().camera_traits(c.cameras.backend).simulated;
      std::vector<fs::path> calibrations{c.calibration};
      if (simulated) {
        for (const auto& scene : test::sim(c).scenes) {
          EXPECT_TRUE(fs::exists(scene.calibration)) << name << ": scene " << scene.name;
          calibrations.push_back(scene.calibration);
        }
      }
      for (const fs::path& calibration : calibrations) {
        if (calibration.empty() || !fs::exists(calibration)) continue;
        EXPECT_EQ(test::error_of([&] { calib::load_calibration(calibration); }), "") << calibration;
      }
      // `epipole-fw --check` on it: the frame loop made with stand-ins for its devices (a
      // simulated board's scene is read from its files, which cross builds cannot read).
      MemoryReport report;
      const std::string check_error = test::error_of([&] { report = check_memory(c); });
      if (simulated && !hal::can_load_scenes()) {
        EXPECT_NE(check_error.find("cannot read image files"), std::string::npos) << check_error;
        continue;
      }
      EXPECT_EQ(check_error, "") << entry.path();
      EXPECT_GT(report.total(), 0u) << entry.path();
    }
  }
  ::unsetenv("EPIPOLE_DATA_DIR");
  // sim, raspberrypi5-ov9281, usb-stereo and the virtual board's two, at least.
  EXPECT_GE(loaded.size(), 5u);
  EXPECT_NE(std::find(loaded.begin(), loaded.end(), "sim/board.yaml"), loaded.end());
}

}  // namespace
}  // namespace epipole::firmware
