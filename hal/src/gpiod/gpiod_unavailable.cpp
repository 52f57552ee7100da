// Built instead of gpiod_trigger.cpp when libgpiod 1.x was not found. EPIPOLE_GPIOD_MISSING
// says why (not found, or libgpiod 2.x).
#include "backends.hpp"
#include "epipole/hal/registry.hpp"

#ifndef EPIPOLE_GPIOD_MISSING
#define EPIPOLE_GPIOD_MISSING "libgpiod 1.x was not found when this binary was built"
#endif

namespace epipole::hal {

void register_gpiod(BackendRegistry& registry) {
  registry.add_unavailable_trigger("gpiod", EPIPOLE_GPIOD_MISSING);
}

}  // namespace epipole::hal
