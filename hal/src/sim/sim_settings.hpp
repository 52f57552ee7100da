#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "epipole/hal/backend_settings.hpp"
#include "epipole/hal/registry.hpp"
#include "sim/sim_files.hpp"
#include "sim/world_settings.hpp"

namespace epipole::hal {

// The right camera turned about its own axes after the calibration (degrees; the axes and signs
// of calib::CameraTurn): the scene's right images are those the turned camera would see.
struct SimDrift {
  double pitch_deg = 0, roll_deg = 0, yaw_deg = 0;
};

// A scene the simulated cameras replay (the board file's sim.scenes.NAME).
struct SimScene {
  std::string name;
  std::vector<std::filesystem::path> left;   // image files, paired in order with right,
  std::vector<std::filesystem::path> right;  // or one video file each (is_video_file())
  std::filesystem::path side_by_side;        // or: one video, the left view in its left half
  std::filesystem::path synthesize;          // or: one image or video, the right view made
  int synthesize_disparity = 0;              // from it at this disparity (pixels)
  std::filesystem::path recording;           // or: an MCAP recording's raw pairs
  std::optional<SimWorld> world;             // or: a world rendered through the calibration
  std::optional<SimDrift> drift;             // the right camera turned since the calibration
  int max_frames = 300;                      // a video or recording of more frames is refused
  std::filesystem::path calibration;         // the rig's, overriding the board's (a
                                             // recording's own when it is replayed; a
                                             // world's is required: its raw images are
                                             // rendered through it)
};

// The board file's `sim:` section (docs/boards.md): what the simulated board replays and how.
struct SimSettings final : BackendSettings {
  std::vector<SimScene> scenes;
  std::string scene;           // the one replayed (epipole-fw --scene)
  bool charge_compute = true;  // the virtual clock advances by the host's processing time
  double drop_rate = 0;        // random faults per frame (both cameras, independent seeds)
  double corrupt_rate = 0;
  std::uint64_t seed = 1;
  // Replayed instead of the scene's files when set (tests; the stand-ins' blank images).
  std::shared_ptr<const StereoImages> images;

  const SimScene& chosen() const;  // the scene replayed (Error when it is none)
  std::unique_ptr<BackendSettings> clone() const override;
  std::filesystem::path calibration() const override;
};

// Reads the section (the registry's SectionBackend::read): option `scene` chooses the scene.
std::unique_ptr<BackendSettings> read_sim_section(const YAML::Node& section,
                                                  const yaml::Fields& file,
                                                  std::span<const BackendOption> options);

// The settings of a board's `sim:` section (Error when it has none): for the host tools and tests
// that drive the simulated board.
SimSettings& sim_settings(BackendSections& sections);
const SimSettings& sim_settings(const BackendSections& sections);

// The scene's images fitted to width x height (letterbox(), sim_scene.hpp), or synthesised, or
// a world rendered through the scene's calibration (world_scene.hpp; of width x height).
// Throws Error naming the file; builds without image files throw saying so.
StereoImages load_scene(const SimScene& scene, int width, int height);
// False in builds without image files, whose simulated board has nothing to replay.
bool can_load_scenes();

}  // namespace epipole::hal
