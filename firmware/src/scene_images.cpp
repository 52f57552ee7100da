// The simulated board's scenes from image and video files (builds with image files).
#include <functional>

#include "epipole/core/error.hpp"
#include "epipole/core/image_io.hpp"
#include "epipole/firmware/board.hpp"
#include "epipole/hal/sim_files.hpp"
#include "epipole/hal/sim_scene.hpp"

namespace epipole::firmware {

namespace {

// The images of a scene's videos; errors name the scene's key (the hal's name the file).
SceneImages from_video(const std::string& key, const std::function<hal::StereoImages()>& load) {
  try {
    hal::StereoImages v = load();
    return SceneImages{std::move(v.left), std::move(v.right)};
  } catch (const Error& e) {
    throw Error(cat(key, ": ", e.what()));
  }
}

}  // namespace

bool can_load_scene_images() {
  return true;
}

SceneImages load_scene_images(const BoardConfig& board) {
  const BoardConfig::SimScene* scene = board.sim_scene();
  require(scene != nullptr, "board ", board.name, ": no simulated scene '", board.sim.scene, "'");
  const int w = board.width();
  const int h = board.height();
  const std::string key = "sim.scenes." + scene->name;
  hal::VideoOptions video;
  video.max_frames = scene->max_frames;
  video.fit_width = w;
  video.fit_height = h;
  if (!scene->side_by_side.empty()) {
    return from_video(key + ".side_by_side",
                      [&] { return hal::load_side_by_side_video(scene->side_by_side, video); });
  }
  SceneImages images;
  if (!scene->synthesize.empty()) {
    if (hal::is_video_file(scene->synthesize)) {
      return from_video(key + ".synthesize", [&] {
        return hal::synthesize_stereo_video(scene->synthesize, scene->synthesize_disparity, video);
      });
    }
    const GrayImage source = load_gray(scene->synthesize);
    images.left.push_back(hal::letterbox(source.view(), w, h));
    images.right.push_back(
        hal::synthesize_right(images.left.back().view(), scene->synthesize_disparity));
    return images;
  }
  const auto any_video = [](const std::vector<std::filesystem::path>& files) {
    for (const auto& f : files) {
      if (hal::is_video_file(f)) return true;
    }
    return false;
  };
  if (any_video(scene->left) || any_video(scene->right)) {
    require(scene->left.size() == 1 && scene->right.size() == 1 &&
                hal::is_video_file(scene->left.front()) && hal::is_video_file(scene->right.front()),
            key, ": left and right must each be one video file, or image files (not a mix)");
    return from_video(key + ".left/right", [&] {
      return hal::load_stereo_videos(scene->left.front(), scene->right.front(), video);
    });
  }
  for (std::size_t i = 0; i < scene->left.size(); ++i) {
    const GrayImage left = load_gray(scene->left[i]);
    const GrayImage right = load_gray(scene->right[i]);
    require(same_size(left.view(), right.view()), "scene ", scene->name, ": ",
            scene->right[i].string(), " is ", right.width(), "x", right.height(), " but ",
            scene->left[i].string(), " is ", left.width(), "x", left.height());
    images.left.push_back(hal::letterbox(left.view(), w, h));
    images.right.push_back(hal::letterbox(right.view(), w, h));
  }
  require(!images.left.empty(), "scene ", scene->name, ": no images");
  return images;
}

}  // namespace epipole::firmware
