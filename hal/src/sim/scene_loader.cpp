// The simulated board's scenes from image and video files, or rendered worlds (builds with image
// files).
#include <functional>

#include "epipole/calib/camera_turn.hpp"
#include "epipole/core/error.hpp"
#include "epipole/core/image_io.hpp"
#include "sim/sim_drift.hpp"
#include "sim/sim_files.hpp"
#include "sim/sim_scene.hpp"
#include "sim/sim_settings.hpp"
#include "sim/world_scene.hpp"

namespace epipole::hal {

namespace {

// The images of a scene's videos; errors name the scene's key (the loaders name the file).
StereoImages from_video(const std::string& key, const std::function<StereoImages()>& load) {
  try {
    return load();
  } catch (const Error& e) {
    throw Error(cat(key, ": ", e.what()));
  }
}

bool any_video(const std::vector<std::filesystem::path>& files) {
  for (const auto& f : files) {
    if (is_video_file(f)) return true;
  }
  return false;
}

StereoImages synthesized(const SimScene& scene, const std::string& key, int w, int h,
                         const VideoOptions& video) {
  if (is_video_file(scene.synthesize)) {
    return from_video(key + ".synthesize", [&] {
      return synthesize_stereo_video(scene.synthesize, scene.synthesize_disparity, video);
    });
  }
  StereoImages images;
  const GrayImage source = load_gray(scene.synthesize);
  images.left.push_back(letterbox(source.view(), w, h));
  images.right.push_back(synthesize_right(images.left.back().view(), scene.synthesize_disparity));
  return images;
}

// The scene's images as its files hold them (or rendered), before any drift.
StereoImages files_of(const SimScene& scene, int w, int h) {
  const std::string key = "sim.scenes." + scene.name;
  VideoOptions video;
  video.max_frames = scene.max_frames;
  video.fit_width = w;
  video.fit_height = h;
  if (scene.world) {
    // Rendered through the rig's calibration, of the cameras' size (never letterboxed).
    try {
      require(!scene.calibration.empty(), "a world scene needs its rig's calibration");
      // A drift is rendered: the right camera where the turn put it (exact, unlike a warp).
      calib::StereoCalibration rig = calib::load_calibration(scene.calibration);
      if (scene.drift) rig = calib::with_right_camera_turned(rig, drift_rotation(*scene.drift));
      return render_world(*scene.world, rig, w, h);
    } catch (const Error& e) {
      throw Error(cat(key, ".world: ", e.what()));
    }
  }
  if (!scene.side_by_side.empty()) {
    return from_video(key + ".side_by_side",
                      [&] { return load_side_by_side_video(scene.side_by_side, video); });
  }
  if (!scene.synthesize.empty()) return synthesized(scene, key, w, h, video);
  if (!scene.recording.empty()) {
    try {
      return load_recording(scene.recording, video);
    } catch (const Error& e) {
      throw Error(cat(key, ".recording: ", e.what()));
    }
  }
  if (any_video(scene.left) || any_video(scene.right)) {
    require(scene.left.size() == 1 && scene.right.size() == 1 &&
                is_video_file(scene.left.front()) && is_video_file(scene.right.front()),
            key, ": left and right must each be one video file, or image files (not a mix)");
    return from_video(key + ".left/right", [&] {
      return load_stereo_videos(scene.left.front(), scene.right.front(), video);
    });
  }
  StereoImages images;
  for (std::size_t i = 0; i < scene.left.size(); ++i) {
    const GrayImage left = load_gray(scene.left[i]);
    const GrayImage right = load_gray(scene.right[i]);
    require(same_size(left.view(), right.view()), "scene ", scene.name, ": ",
            scene.right[i].string(), " is ", right.width(), "x", right.height(), " but ",
            scene.left[i].string(), " is ", left.width(), "x", left.height());
    images.left.push_back(letterbox(left.view(), w, h));
    images.right.push_back(letterbox(right.view(), w, h));
  }
  require(!images.left.empty(), "scene ", scene.name, ": no images");
  return images;
}

}  // namespace

StereoImages load_scene(const SimScene& scene, int w, int h) {
  StereoImages images = files_of(scene, w, h);
  if (scene.drift && !scene.world) {
    try {
      drift_right_images(images, calib::load_calibration(scene.calibration), *scene.drift);
    } catch (const Error& e) {
      throw Error(cat("sim.scenes.", scene.name, ".drift: ", e.what()));
    }
  }
  return images;
}

bool can_load_scenes() {
  return true;
}

}  // namespace epipole::hal
