// Builds without image files (libpng/libjpeg not found for the target).
#include "epipole/core/error.hpp"
#include "epipole/firmware/board.hpp"

namespace epipole::firmware {

bool can_load_scene_images() {
  return false;
}

SceneImages load_scene_images(const BoardConfig& board) {
  throw Error(cat("board ", board.name,
                  ": this build cannot read image files (it was built "
                  "without libpng and libjpeg), so the simulated cameras have nothing to replay"));
}

}  // namespace epipole::firmware
