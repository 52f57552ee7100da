#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "epipole/calib/calibration.hpp"
#include "epipole/firmware/board_config.hpp"
#include "epipole/firmware/command_memory.hpp"
#include "epipole/firmware/health_report.hpp"
#include "epipole/firmware/memory_report.hpp"
#include "epipole/firmware/pipeline.hpp"
#include "epipole/firmware/protocol/messages.hpp"
#include "epipole/hal/clock.hpp"

namespace epipole::firmware {

namespace outputs {
class Output;
}

// What one output did with the pairs offered to it (docs/outputs.md).
struct OutputReport {
  std::string name;
  std::uint64_t delivered = 0;
  std::uint64_t dropped = 0;   // its work was behind: replaced by a fresher pair before it started
  std::uint64_t failures = 0;  // its work threw (counted, said in the journal, gone on)
  std::uint64_t work_ns = 0;   // its work's time on the delivered pairs, summed
};

// The outputs the board file turns on (`outputs:`, docs/outputs.md), each made with all its
// memory by the constructor (which throws Error when one cannot work) and run on a thread of
// its own between start() and stop(). The frame loop offers each of them every processed pair and
// every health message; publish() copies what each keeps and never waits for their work.
class Outputs {
 public:
  // `offline`: made to be measured only (epipole-fw --check): nothing joins a network.
  Outputs(const BoardConfig& config, const std::optional<calib::StereoCalibration>& calibration,
          bool offline = false);
  ~Outputs();
  Outputs(const Outputs&) = delete;
  Outputs& operator=(const Outputs&) = delete;

  void start();
  void stop();
  // Frame loop side. `age`: how long ago, on the board's clock, the pair's trigger edge was
  // (its time on the system clock is now minus that).
  void publish(const FrameResult& result, hal::Nanoseconds age);
  void publish_health(const HealthReport& report);
  // A command for an output (`record`): the verdict of the output that takes it, unsupported
  // when none does. `now`: the board's clock.
  CommandVerdict command(const protocol::Message& command, hal::Nanoseconds now);

  bool empty() const { return outputs_.empty(); }
  std::vector<OutputReport> reports() const;
  // Summed over the outputs, for health.
  std::uint64_t dropped() const;
  std::uint64_t failures() const;
  // One part per output ("output <name>").
  void add_memory(MemoryReport& report) const;

 private:
  std::vector<std::string> names_;
  std::vector<std::unique_ptr<outputs::Output>> outputs_;
};

}  // namespace epipole::firmware
