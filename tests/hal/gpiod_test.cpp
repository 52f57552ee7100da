#include <gtest/gtest.h>

#include <string>

#include "epipole/core/error.hpp"
#include "epipole/hal/gpiod_trigger.hpp"
#include "epipole/hal/registry.hpp"

namespace epipole::hal {
namespace {

std::string error_of(const TriggerConfig& config) {
  try {
    GpiodTrigger trigger(config);
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

TEST(GpiodTrigger, MissingLinesAndChipsAreNamed) {
  TriggerConfig config;
  config.line = "EPIPOLE_NO_SUCH_LINE";
  EXPECT_NE(error_of(config).find("trigger EPIPOLE_NO_SUCH_LINE: no GPIO line"), std::string::npos)
      << error_of(config);
  config.chip = "/dev/gpiochip-epipole-missing";
  EXPECT_NE(error_of(config).find("/dev/gpiochip-epipole-missing"), std::string::npos)
      << error_of(config);
  config.chip.clear();
  config.rate_hz = 5000.0;
  EXPECT_NE(error_of(config).find("rate 5000 Hz"), std::string::npos) << error_of(config);
  config.rate_hz = 30.0;
  config.pulse_width = 0;
  EXPECT_NE(error_of(config).find("pulse width"), std::string::npos) << error_of(config);
}

TEST(GpiodTrigger, IsBuiltIntoTheRegistry) {
  TriggerConfig config;
  config.line = "EPIPOLE_NO_SUCH_LINE";
  try {
    BackendRegistry::builtin().create_trigger("gpiod", config);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).find("not built"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("EPIPOLE_NO_SUCH_LINE"), std::string::npos);
  }
}

}  // namespace
}  // namespace epipole::hal
