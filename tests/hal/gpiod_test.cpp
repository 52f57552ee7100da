#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "epipole/core/error.hpp"
#include "epipole/hal/registry.hpp"
#include "gpiod/gpiod_trigger.hpp"

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

// A line that is not there is no configuration error: the trigger starts without it, says why
// and reports it lost until it appears (the virtual board and the deployment test run real lines).
std::string reason_after_start(const TriggerConfig& config) {
  GpiodTrigger trigger(config);
  EXPECT_FALSE(trigger.available());
  trigger.start();
  EXPECT_FALSE(trigger.available());
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(trigger.wait_edge(20'000'000).status, EdgeStatus::lost);
  }
  std::string reason = trigger.unavailable_reason();
  trigger.stop();
  EXPECT_EQ(trigger.unavailable_reason(), "stopped");
  return reason;
}

TEST(GpiodTrigger, MissingLinesAndChipsAreWaitedFor) {
  TriggerConfig config;
  config.line = "EPIPOLE_NO_SUCH_LINE";
  for (const TriggerRole role : {TriggerRole::master, TriggerRole::slave}) {
    config.role = role;
    config.chip.clear();
    EXPECT_NE(reason_after_start(config).find("no GPIO line of that name on any chip"),
              std::string::npos);
    config.chip = "/dev/gpiochip-epipole-missing";
    EXPECT_NE(
        reason_after_start(config).find("cannot open GPIO chip /dev/gpiochip-epipole-missing"),
        std::string::npos);
  }
}

TEST(GpiodTrigger, ImpossibleSettingsAreNamed) {
  TriggerConfig config;
  config.line = "EPIPOLE_NO_SUCH_LINE";
  config.rate_hz = 5000.0;
  EXPECT_NE(error_of(config).find("rate 5000 Hz"), std::string::npos) << error_of(config);
  config.rate_hz = 30.0;
  config.pulse_width = 0;
  EXPECT_NE(error_of(config).find("pulse width"), std::string::npos) << error_of(config);
}

TEST(GpiodTrigger, IsBuiltIntoTheRegistry) {
  TriggerConfig config;
  config.line = "EPIPOLE_NO_SUCH_LINE";
  const std::unique_ptr<TriggerLine> line =
      BackendRegistry::builtin().create_trigger("gpiod", config);
  ASSERT_NE(line, nullptr);
  line->start();
  EXPECT_FALSE(line->available());
  EXPECT_NE(line->unavailable_reason().find("no GPIO line"), std::string::npos)
      << line->unavailable_reason();
}

}  // namespace
}  // namespace epipole::hal
