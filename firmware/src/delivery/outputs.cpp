#include "epipole/firmware/outputs.hpp"

#include "output_files.hpp"
#include "outputs/output.hpp"
#include "system_time.hpp"

namespace epipole::firmware {

Outputs::Outputs(const BoardConfig& config,
                 const std::optional<calib::StereoCalibration>& calibration, bool offline) {
  const outputs::OutputContext context{config, calibration, offline};
  for (const outputs::OutputFile& file : outputs::kOutputFiles) {
    if (config.outputs.find(file.name) == nullptr) continue;
    names_.emplace_back(file.name);
    outputs_.push_back(file.definition->make(context));
  }
}

Outputs::~Outputs() {
  stop();
}

void Outputs::start() {
  for (const auto& o : outputs_) o->start();
}

void Outputs::stop() {
  for (const auto& o : outputs_) o->stop();
}

void Outputs::publish(const FrameResult& result, hal::Nanoseconds age) {
  if (outputs_.empty()) return;
  const outputs::PairStamp stamp{result.trigger_ns, detail::system_now_ns() - age};
  for (const auto& o : outputs_) o->offer(result, stamp);
}

void Outputs::publish_health(const HealthReport& report) {
  for (const auto& o : outputs_) o->offer_health(report);
}

CommandVerdict Outputs::command(const protocol::Message& command, hal::Nanoseconds now) {
  for (const auto& o : outputs_) {
    if (const std::optional<CommandVerdict> v = o->command(command, now)) return *v;
  }
  return {protocol::AckStatus::unsupported, protocol::AckReason::none};
}

std::vector<OutputReport> Outputs::reports() const {
  std::vector<OutputReport> reports;
  for (std::size_t i = 0; i < outputs_.size(); ++i) {
    const outputs::DeliveryCounters c = outputs_[i]->counters();
    reports.push_back({names_[i], c.delivered, c.dropped, c.failures, c.work_ns});
  }
  return reports;
}

std::uint64_t Outputs::dropped() const {
  std::uint64_t sum = 0;
  for (const auto& o : outputs_) sum += o->counters().dropped;
  return sum;
}

std::uint64_t Outputs::failures() const {
  std::uint64_t sum = 0;
  for (const auto& o : outputs_) sum += o->counters().failures;
  return sum;
}

void Outputs::add_memory(MemoryReport& report) const {
  for (std::size_t i = 0; i < outputs_.size(); ++i) {
    report.add("output " + names_[i], outputs_[i]->working_set_bytes());
  }
}

}  // namespace epipole::firmware
