#pragma once

// An output: somewhere a pair's results go besides the serial link (a recording, a ROS 2 graph,
// a live view). firmware/src/outputs/<name>.cpp defines `extern constinit const OutputDefinition
// <name>_output` (declared by the generated output_files.hpp, which it includes): how to read its
// subsection of the board file's `outputs` and how to make it, with all its memory, when the file
// has that subsection. Made, it is offered every processed pair and every health message on the
// frame loop's thread and does its work on a thread of its own (delivery/pair_delivery.hpp).

#include <cstddef>
#include <memory>
#include <optional>
#include <string_view>

#include "delivery/pair_copy.hpp"
#include "delivery/pair_delivery.hpp"
#include "epipole/calib/calibration.hpp"
#include "epipole/core/error.hpp"
#include "epipole/firmware/board_config.hpp"
#include "epipole/firmware/command_memory.hpp"
#include "epipole/firmware/pipeline.hpp"

namespace YAML {
class Node;
}
namespace epipole::yaml {
class Fields;
}

namespace epipole::firmware::outputs {

// What the outputs of one firmware share, made before them.
struct OutputContext {
  const BoardConfig& board;
  const std::optional<calib::StereoCalibration>& calibration;  // none: uncalibrated
  // Made to be measured only (epipole-fw --check): buffers allocated, nothing joined or opened
  // that others would see (a network).
  bool offline = false;
};

// The settings an output read from its subsection (OutputDefinition::read_settings).
template <class Settings>
const Settings& settings_of(const OutputContext& context, std::string_view output) {
  const OutputSettings* read = context.board.outputs.find(output);
  const auto* settings = dynamic_cast<const Settings*>(read);
  require(settings != nullptr, "output ", output, ": made without its settings");
  return *settings;
}

class Output {
 public:
  virtual ~Output() = default;

  // Its thread, once the firmware's devices have started; stop() returns once it stopped.
  virtual void start() = 0;
  virtual void stop() = 0;
  // Frame loop side: never waits for the output's work, never allocates.
  virtual void offer(const FrameResult& result, const PairStamp& stamp) = 0;
  virtual void offer_health(const HealthReport& /*report*/) {}
  // A command from the robot that the output takes (the recording's `record`), on the frame
  // loop's thread, never waiting; nothing when it is not one of its own. `now`: the board's clock.
  virtual std::optional<CommandVerdict> command(const protocol::Message& /*command*/,
                                                hal::Nanoseconds /*now*/) {
    return std::nullopt;
  }

  virtual DeliveryCounters counters() const = 0;
  // Every buffer it allocated for its work.
  virtual std::size_t working_set_bytes() const = 0;
};

// What an output's file defines, as `extern constinit const OutputDefinition <name>_output`.
struct OutputDefinition {
  // Reads its subsection (`outputs: {<name>: ...}`; a null node for `<name>:` alone: its
  // defaults), throwing Error through `fields` for a bad value.
  std::unique_ptr<OutputSettings> (*read_settings)(const YAML::Node& section,
                                                   const yaml::Fields& fields);
  // Makes it (throws Error when it cannot work: a folder that cannot be made, ...).
  std::unique_ptr<Output> (*make)(const OutputContext& context);
};

// A file of firmware/src/outputs/ and what it defines (the generated output_files.hpp).
struct OutputFile {
  std::string_view name;
  const OutputDefinition* definition;
};

}  // namespace epipole::firmware::outputs
