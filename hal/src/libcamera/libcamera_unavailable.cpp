// Built instead of libcamera_camera.cpp when libcamera was not found (or not looked for: cross
// builds without a sysroot). EPIPOLE_LIBCAMERA_MISSING says why.
#include "backends.hpp"
#include "epipole/hal/registry.hpp"
#include "libcamera/libcamera_camera.hpp"

#ifndef EPIPOLE_LIBCAMERA_MISSING
#define EPIPOLE_LIBCAMERA_MISSING "libcamera was not found when this binary was built"
#endif

namespace epipole::hal {

void register_libcamera(BackendRegistry& registry) {
  registry.add_unavailable_camera("libcamera", EPIPOLE_LIBCAMERA_MISSING);
}

std::string libcamera_build_version() {
  return {};
}

}  // namespace epipole::hal
