// Built instead of gpiod_trigger.cpp when libgpiod 1.x was not found.
#include "epipole/hal/gpiod_trigger.hpp"
#include "epipole/hal/registry.hpp"

namespace epipole::hal {

void register_gpiod(BackendRegistry& registry) {
  registry.add_unavailable_trigger(
      "gpiod", "libgpiod 1.x (gpiod.h and the library) was not found when this binary was built");
}

}  // namespace epipole::hal
