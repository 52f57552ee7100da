// The simulated board's scenes from image files (builds with image files).
#include "epipole/core/error.hpp"
#include "epipole/core/image_io.hpp"
#include "epipole/firmware/board.hpp"
#include "epipole/hal/sim.hpp"
#include "epipole/hal/sim_scene.hpp"

namespace epipole::firmware {

SceneImages load_scene_images(const BoardConfig& board) {
  const BoardConfig::SimScene* scene = board.sim_scene();
  require(scene != nullptr, "board ", board.name, ": no simulated scene '", board.sim.scene, "'");
  const int w = board.width();
  const int h = board.height();
  SceneImages images;
  if (!scene->synthesize.empty()) {
    const GrayImage source = load_gray(scene->synthesize);
    images.left.push_back(hal::letterbox(source.view(), w, h));
    images.right.push_back(
        hal::synthesize_right(images.left.back().view(), scene->synthesize_disparity));
    return images;
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
