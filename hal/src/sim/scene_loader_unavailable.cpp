// Builds without image files (libpng/libjpeg not found for the target).
#include "epipole/core/error.hpp"
#include "sim/sim_settings.hpp"

namespace epipole::hal {

bool can_load_scenes() {
  return false;
}

StereoImages load_scene(const SimScene& scene, int /*width*/, int /*height*/) {
  throw Error(cat("sim.scenes.", scene.name,
                  ": this build cannot read image files (it was built without libpng and "
                  "libjpeg), so the simulated cameras have nothing to replay"));
}

}  // namespace epipole::hal
