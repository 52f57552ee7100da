#pragma once

// A small simulated board for firmware tests that run everywhere (no data files): textured
// images with a known constant disparity, an ideal rectified rig, and the board file around
// them in a temporary folder.
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <string>

#include <fstream>

#include "cascade_test_models.hpp"
#include "epipole/calib/calibration.hpp"
#include "epipole/core/temporary_folder.hpp"
#include "epipole/firmware/board.hpp"
#include "epipole/firmware/board_config.hpp"
#include "random_image.hpp"
#include "sim/sim.hpp"
#include "sim/sim_scene.hpp"
#include "sim/sim_settings.hpp"

namespace epipole::test {

// A temporary folder, removed with everything in it when the object goes.
class TempDir : public TemporaryFolder {
 public:
  TempDir() : TemporaryFolder("epipole-test") {}
};

// An ideal rectified rig: focal length f pixels, baseline b metres, centred principal points.
inline calib::StereoCalibration ideal_rig(int width, int height, double f, double b) {
  calib::StereoCalibration c;
  c.width = width;
  c.height = height;
  const double cx = (width - 1) / 2.0;
  const double cy = (height - 1) / 2.0;
  for (calib::CameraCalibration* cam : {&c.left, &c.right}) {
    cam->camera.intrinsics = {f, f, cx, cy};
    cam->camera.distortion = {0, 0, 0, 0, 0};
    cam->projection << f, 0, cx, 0, 0, f, cy, 0, 0, 0, 1, 0;
  }
  c.left.id = "left";
  c.right.id = "right";
  c.T << -b, 0, 0;
  c.right.projection(0, 3) = -f * b;
  c.Q << 1, 0, 0, -cx, 0, 1, 0, -cy, 0, 0, 0, f, 0, 0, 1 / b, 0;
  c.date = "2026-01-01T00:00:00Z";
  c.source = "tests/firmware/sim_rig.hpp";
  return c;
}

// The board's `sim:` section (the simulated board's settings: faults, charging compute).
inline hal::SimSettings& sim(firmware::BoardConfig& config) {
  return hal::sim_settings(config.sections);
}
inline const hal::SimSettings& sim(const firmware::BoardConfig& config) {
  return hal::sim_settings(config.sections);
}

// The simulated board of a firmware.
inline hal::SimBoard& sim_board(firmware::Board& board) {
  hal::SimBoard* sim = hal::simulated_board(board.hardware());
  if (sim == nullptr) throw std::logic_error("sim_rig.hpp: not a simulated board");
  return *sim;
}

struct SimRig {
  static constexpr double kFocal = 100.0;
  static constexpr double kBaseline = 0.1;

  TempDir dir;
  int width;
  int height;
  int disparity;
  firmware::BoardConfig config;

  // The pair: textured left image, right view at `disparity`, `images` of them (different
  // textures).
  hal::StereoImages images(int count = 2) const {
    hal::StereoImages s;
    for (int i = 0; i < count; ++i) {
      GrayImage left(width, height);
      fill(left.view(), Pattern::blobs, static_cast<std::uint32_t>(11 + i));
      s.right.push_back(hal::synthesize_right(left.view(), disparity));
      s.left.push_back(std::move(left));
    }
    return s;
  }
  // The configuration with the simulated cameras replaying images(count).
  firmware::BoardConfig replaying(firmware::BoardConfig c, int count = 2) const {
    sim(c).images = std::make_shared<const hal::StereoImages>(images(count));
    return c;
  }
  double depth() const { return kFocal * kBaseline / disparity; }

  // Detection on, with a random cascade compiled into the rig's folder (it fires on the
  // textured images often enough to exercise the stage; the boxes mean nothing).
  void add_cascade(firmware::BoardConfig& c) const {
    RandomCascadeShape shape;
    shape.window_width = shape.window_height = 20;
    shape.stages = 5;
    shape.pass_rate = 0.6;
    const std::vector<std::uint8_t> binary =
        vision::CascadeModel(random_cascade(shape, 3), "random").to_binary();
    const std::filesystem::path file = dir.path() / "cascade.bin";
    std::ofstream(file, std::ios::binary)
        .write(reinterpret_cast<const char*>(binary.data()),
               static_cast<std::streamsize>(binary.size()));
    c.stages |= protocol::stage_bit(protocol::Stage::detect);
    c.detector.cascade = file;
    c.detector.min_size = 20;
  }

  // The board file's text; `extra` is appended (more top-level keys).
  std::string yaml(const std::string& extra = "") const {
    return "version: 1\nname: test-sim\n"
           "cameras: {backend: sim, left: left, right: right, width: " +
           std::to_string(width) + ", height: " + std::to_string(height) +
           ", trigger: external, timeout_ms: 100}\n"
           "trigger: {backend: sim, line: sim, rate_hz: 30}\n"
           "serial: {backend: none}\n"
           "calibration: rig.yaml\n"
           "stereo: {max_disparity: 32}\n"
           "corners: {max_corners: 500}\n"
           "stages: {sparse: false, detect: false}\n"
           "sim: {charge_compute: false, scenes: {test: {synthesize: unused.png, disparity: " +
           std::to_string(disparity) + "}}}\n" +
           // One thread unless the test says otherwise: the default, the CPUs of the machine
           // running the test, would make results and memory depend on it.
           (extra.find("threads:") == std::string::npos ? "threads: {count: 1}\n" : "") + extra;
  }
  firmware::BoardConfig parse(const std::string& extra = "") const {
    return firmware::parse_board_config(yaml(extra), dir.path() / "board.yaml");
  }
  // The same board without a trigger line: both cameras free running at 30 fps (as the
  // usb-stereo board), so the frame loop pairs their frames by time.
  firmware::BoardConfig parse_free_running(const std::string& extra = "") const {
    std::string text = yaml(extra);
    const auto swap = [&](const std::string& from, const std::string& to) {
      const std::size_t at = text.find(from);
      if (at == std::string::npos) throw std::logic_error("sim_rig.hpp: no '" + from + "'");
      text.replace(at, from.size(), to);
    };
    swap("trigger: external", "trigger: free_running");
    swap("trigger: {backend: sim, line: sim, rate_hz: 30}", "trigger: {backend: none}");
    return firmware::parse_board_config(text, dir.path() / "board.yaml");
  }

  SimRig(int w = 160, int h = 96, int d = 8, const std::string& extra = "")
      : width(w), height(h), disparity(d) {
    calib::save_calibration(dir.path() / "rig.yaml", ideal_rig(w, h, kFocal, kBaseline));
    config = parse(extra);
  }
};

}  // namespace epipole::test
