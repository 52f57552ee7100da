#include "epipole/firmware/frame_loop.hpp"
#include "epipole/core/angles.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <string_view>
#include <tuple>

#include "epipole/core/error.hpp"
#include "epipole/firmware/journal.hpp"
#include "epipole/firmware/link_budget.hpp"
#include "epipole/firmware/odometry_messages.hpp"
#include "epipole/firmware/pair_messages.hpp"
#include "epipole/firmware/protocol/mavlink.hpp"
#include "epipole/firmware/thread_roles.hpp"
#include "steady_time.hpp"

namespace epipole::firmware {

using detail::steady_now;

using protocol::Stage;

namespace {

// The link's thread goes round every few milliseconds, and gives up a write the port takes
// nothing of within Link::kStuckWrite: longer than this, it is stuck.
constexpr hal::Nanoseconds kLinkAlive = 2 * Link::kStuckWrite;

std::unique_ptr<TriggerWatch> make_trigger_watch(const BoardConfig& config, Board& board) {
  if (board.trigger() == nullptr) return nullptr;
  const hal::Nanoseconds period = hal::period_of(config.trigger.line.rate_hz);
  return std::make_unique<TriggerWatch>(*board.trigger(), period);
}

}  // namespace

hal::PairingConfig pairing_config(const BoardConfig& config,
                                  std::optional<hal::Nanoseconds> camera_edge_delay) {
  hal::PairingConfig p = config.pairing;
  if (!config.has_trigger()) {
    // Free-running cameras count their frames each on its own: pairs are matched by time, and
    // the tolerance must be below half the frame period of the faster camera.
    p.trigger_period = config.frame_period();
  }
  if (config.pairing_edge_delay) {
    p.edge_delay = *config.pairing_edge_delay;
  } else if (camera_edge_delay) {
    p.edge_delay = *camera_edge_delay;
  }
  return p;
}

namespace {

// set_exposure: exposure_us in microseconds and gain_centidb in hundredths of a decibel, 0 for
// automatic as in the board file; the HAL's gain is the multiplier 10^(dB / 20).
hal::Nanoseconds exposure_of(const protocol::SetExposure& command) {
  return hal::Nanoseconds{command.exposure_us} * 1000;
}
double gain_of(const protocol::SetExposure& command) {
  return command.gain_centidb == 0 ? 0.0 : std::pow(10.0, command.gain_centidb / 2000.0);
}

}  // namespace

FrameLoop::FrameLoop(const BoardConfig& config, Board& board, Pipeline& pipeline, Link& link,
                     Outputs* outputs)
    : config_(config),
      board_(board),
      pipeline_(pipeline),
      link_(link),
      outputs_(outputs),
      trigger_(make_trigger_watch(config, board)),
      grabber_(board.left(), board.right(), board.clock(),
               pairing_config(config, board.left().edge_delay()),
               trigger_ ? &trigger_->record() : nullptr),
      health_(board.clock().now()),
      snapshots_(config.snapshot_directory, config.width(), config.height(),
                 {config.snapshot_limit,
                  static_cast<std::uint64_t>(config.snapshot_min_free_mb * 1024 * 1024)}),
      stages_(config.stages | protocol::kAlwaysOnStages),
      // The board names its calibration file, and none was loaded: it does not exist yet (a
      // file that does not read, or a backend section's, stops the firmware at start-up).
      not_calibrated_(!config.calibration.empty() && !pipeline.has_calibration()),
      no_cascade_(!pipeline.missing_cascade().empty()) {}

FrameLoop::~FrameLoop() {
  finish();
  board_.left_recovery().follow_trigger(nullptr);  // the record goes with the loop
  board_.right_recovery().follow_trigger(nullptr);
}

void FrameLoop::start() {
  if (started_) return;
  started_at_ = board_.clock().now();
  if (trigger_) {  // triggered cameras wait for the trigger's edges, never reopened for them
    board_.left_recovery().follow_trigger(&trigger_->record());
    board_.right_recovery().follow_trigger(&trigger_->record());
  }
  board_.left().start();
  board_.right().start();
  if (trigger_) trigger_->start();
  if (const hal::RecoveringSerialPort* serial = board_.serial_recovery()) {
    serial_connected_ = serial->connected();
    if (!serial_connected_ && device_lines_[3].begins(started_at_)) {  // said: so is its return
      journal(Priority::warning, "serial port %s is not there yet: waiting for it",
              config_.serial.port.device.c_str());
    }
  }
  link_.start();
  if (outputs_ != nullptr) outputs_->start();
  if (link_.protocol() == LinkProtocol::mavlink) link_.publish_heartbeat(heartbeat_status());
  started_ = true;
}

void FrameLoop::finish() {
  if (!started_) return;
  started_ = false;
  if (ahead_.result && ahead_.result->status == hal::PairStatus::ok) {
    grabber_.release(ahead_.result->pair);  // taken ahead, not processed
  }
  ahead_.result.reset();
  pipeline_.drop_pair_ahead();
  if (trigger_) trigger_->stop();
  board_.left().stop();
  board_.right().stop();
  if (!snapshots_.flush(SnapshotWriter::kStopWait)) {
    journal(Priority::warning,
            "snapshot: still being written after %lld ms (a stalled file "
            "system?): stopping without it",
            static_cast<long long>(SnapshotWriter::kStopWait.count()));
  }
  // Before the link goes: the robot hears of every snapshot it asked for.
  answer_snapshots();
  answer_corrections(/*stopping=*/true);
  if (snapshot_pending_) {  // asked for, but no pair came before the stop
    snapshot_pending_ = false;
    conclude(snapshot_sequence_, {protocol::AckStatus::rejected, protocol::AckReason::failed});
  }
  link_.stop();
  if (outputs_ != nullptr) outputs_->stop();
}

FrameLoop::Verdict FrameLoop::request_snapshot(std::uint16_t sequence) {
  using protocol::AckReason;
  using protocol::AckStatus;
  if (snapshot_pending_) return {AckStatus::rejected, AckReason::busy};
  // With a camera gone or the trigger stopped no pair may come for long: refused at once.
  const bool no_pairs =
      board_.left_recovery().recovering() || board_.right_recovery().recovering() || trigger_quiet_;
  if (no_pairs && snapshots_.enabled()) return {AckStatus::rejected, AckReason::no_pairs};
  switch (snapshots_.can_take()) {
    case SnapshotRefusal::none:
      snapshot_pending_ = true;  // taken from the next pair, answered once written
      snapshot_sequence_ = sequence;
      snapshot_asked_at_ = board_.clock().now();
      return {AckStatus::ok, AckReason::none};
    case SnapshotRefusal::disabled:
      return {AckStatus::unsupported, AckReason::none};
    case SnapshotRefusal::busy:
      return {AckStatus::rejected, AckReason::busy};
    case SnapshotRefusal::limit:
    case SnapshotRefusal::no_space:
    case SnapshotRefusal::unreadable:
      break;
  }
  return {AckStatus::rejected, AckReason::storage};
}

void FrameLoop::answer_snapshots() {
  while (const std::optional<SnapshotDone> done = snapshots_.finished()) {
    conclude(done->sequence,
             done->ok ? Verdict{protocol::AckStatus::ok, protocol::AckReason::none}
                      : Verdict{protocol::AckStatus::rejected, protocol::AckReason::failed});
  }
}

FaultCounts FrameLoop::faults() {
  FaultCounts f;
  const hal::PairingCounters& p = grabber_.pairer().counters();
  const auto& l = board_.left_recovery().counters();
  const auto& r = board_.right_recovery().counters();
  f.unpaired_frames = p.left().unpaired + p.right().unpaired;
  f.triggers = grabber_.pairer().ledger().at_newest_published();
  f.camera_timeouts = l.timeouts + r.timeouts;
  f.camera_reopens = l.reopens + r.reopens;
  if (trigger_) {
    f.trigger_losses = trigger_->losses();
    f.trigger_bounces = trigger_->bounces();
  }
  f.pairs_off_trigger = p.left().off_trigger;  // a pair's two frames, counted on each side
  if (const hal::RecoveringSerialPort* s = board_.serial_recovery()) {
    f.link_reopens = s->reopens();  // counted on the link's thread
  }
  const LinkCounters link = link_.counters();
  f.bad_commands = link.rejected_frames + rejected_commands_;
  f.messages_dropped = link.messages_dropped;
  f.snapshot_failures = snapshots_.failures();
  if (outputs_ != nullptr) {
    f.outputs_dropped = outputs_->dropped();
    f.output_failures = outputs_->failures();
  }
  return f;
}

void FrameLoop::send(const protocol::Message& message) {
  link_.publish(message);
  if (observer_ != nullptr) observer_->on_message(message);
}

void FrameLoop::apply_commands() {
  using protocol::AckReason;
  using protocol::AckStatus;
  Command c;
  // At most a queue's worth a turn: a robot that floods the link cannot hold up the pairs.
  for (std::size_t n = 0; n < Link::kMaxCommands && link_.next_command(c); ++n) {
    ++summary_.commands;
    if (c.overflow) {  // not applied, not remembered: sent again, it is applied
      answer(c.sequence, {AckStatus::rejected, AckReason::busy});
      continue;
    }
    const hal::Nanoseconds now = board_.clock().now();
    if (const CommandMemory::Entry* first = commands_.resent(c.sequence, c.message, now)) {
      ++summary_.resent_commands;
      if (!first->pending) answer(c.sequence, first->verdict);  // else: answered once written
      continue;
    }
    Verdict v{AckStatus::rejected, AckReason::not_a_command};
    if (const auto* s = std::get_if<protocol::SetStages>(&c.message)) {
      v = {AckStatus::rejected, AckReason::out_of_range};
      if ((s->enabled_mask & ~protocol::kAllStages) == 0) {
        stages_ = static_cast<StageMask>(s->enabled_mask | protocol::kAlwaysOnStages);
        v = {AckStatus::ok, AckReason::none};
      }
    } else if (std::holds_alternative<protocol::Snapshot>(c.message)) {
      v = request_snapshot(c.sequence);
    } else if (const auto* t = std::get_if<protocol::SetTriggerRate>(&c.message)) {
      v = set_trigger_rate(*t);
    } else if (const auto* e = std::get_if<protocol::SetExposure>(&c.message)) {
      v = set_exposure(*e);
    } else if (std::holds_alternative<protocol::Record>(c.message)) {
      v = outputs_ != nullptr ? outputs_->command(c.message, now)
                              : Verdict{AckStatus::unsupported, AckReason::none};
    } else if (std::holds_alternative<protocol::Recalibrate>(c.message)) {
      v = recalibrate(c.sequence);
    } else if (std::holds_alternative<protocol::SaveCalibration>(c.message)) {
      v = save_calibration(c.sequence);
    }
    // Answered once done: a snapshot once written, a correction once in place, a file once
    // written.
    const bool pending = v.status == AckStatus::ok &&
                         (std::holds_alternative<protocol::Snapshot>(c.message) ||
                          (std::holds_alternative<protocol::Recalibrate>(c.message) &&
                           recalibrate_pending_ && recalibrate_sequence_ == c.sequence) ||
                          std::holds_alternative<protocol::SaveCalibration>(c.message));
    if (v.reason != AckReason::busy) commands_.remember(c.sequence, c.message, now, v, pending);
    if (!pending) answer(c.sequence, v);
  }
}

void FrameLoop::answer(std::uint16_t sequence, Verdict verdict) {
  protocol::CommandAck ack;
  ack.command_sequence = sequence;
  ack.status = verdict.status;
  ack.reason = verdict.reason;
  if (verdict.status != protocol::AckStatus::ok) ++rejected_commands_;  // health's bad_commands
  send(ack);
}

// No edge for three trigger periods (none at all yet: from three periods after the start).
bool FrameLoop::trigger_quiet() const {
  const hal::Nanoseconds now = board_.clock().now();
  const std::optional<hal::Nanoseconds> newest = trigger_->record().newest(board_.clock().id());
  return now - newest.value_or(started_at_) > 3 * frame_period();
}

// What the refusals' journal line adds when lines were left out before it.
std::string FrameLoop::left_out() const {
  const std::uint64_t n = refusals_said_.left_out();
  return n == 0 ? std::string() : cat(" (", n, " refusals not said since the last)");
}

// A pending command's result (a snapshot's): remembered for its resends, and answered.
void FrameLoop::conclude(std::uint16_t sequence, Verdict verdict) {
  commands_.settle(sequence, verdict);
  answer(sequence, verdict);
}

// The period frames come at now: the trigger's (set_trigger_rate changes it), or free running
// the cameras'.
hal::Nanoseconds FrameLoop::frame_period() const {
  if (const hal::Nanoseconds p = grabber_.pairer().config().trigger_period; p > 0) return p;
  return config_.frame_period();
}

FrameLoop::Verdict FrameLoop::set_trigger_rate(const protocol::SetTriggerRate& command) {
  using protocol::AckReason;
  using protocol::AckStatus;
  hal::TriggerLine* line = board_.trigger();
  if (line == nullptr || !trigger_) return {AckStatus::unsupported, AckReason::none};
  const double rate_hz = command.rate_millihz / 1000.0;
  const auto rejected = [&](AckReason reason, const std::string& why) {
    if (refusals_said_.allow(steady_now())) {
      journal(Priority::warning, "set_trigger_rate %u mHz rejected: %s%s",
              static_cast<unsigned>(command.rate_millihz), why.c_str(), left_out().c_str());
    }
    return Verdict{AckStatus::rejected, reason};
  };
  hal::StereoPairer& pairer = grabber_.pairer();
  const hal::Nanoseconds old_period = pairer.config().trigger_period;
  try {
    hal::with_rate(line->config(), rate_hz);  // a possible rate (and a master line) first
  } catch (const Error& e) {
    return rejected(AckReason::out_of_range, e.what());
  }
  const hal::Nanoseconds period = hal::period_of(rate_hz);
  for (const hal::CameraSource* camera : {&board_.left(), &board_.right()}) {
    if (const auto shortest = camera->shortest_frame_period(); shortest && period < *shortest) {
      return rejected(AckReason::out_of_range,
                      cat("camera ", camera->name(), " can follow at most ",
                          std::llround(1e9 / static_cast<double>(*shortest)), " Hz"));
    }
  }
  const hal::Nanoseconds exposure =
      std::max(board_.left().config().exposure, board_.right().config().exposure);
  if (const std::string problem = frame_timing_problem(period, exposure, config_.cameras.timeout);
      !problem.empty()) {
    return rejected(AckReason::timing, problem);
  }
  try {
    pairer.set_trigger_period(period);  // the tolerances must stay below half the period
  } catch (const Error& e) {
    return rejected(AckReason::timing, e.what());
  }
  if (config_.has_link()) {  // the summaries must fit the link at the new rate
    if (const std::string problem = link_capacity_problem(
            link_.protocol(), config_.serial.port.baud, period, odometry_runs());
        !problem.empty()) {
      pairer.set_trigger_period(old_period);
      return rejected(AckReason::out_of_range, problem);
    }
  }
  try {
    line->set_rate(rate_hz);
  } catch (const Error& e) {
    pairer.set_trigger_period(old_period);
    return rejected(AckReason::out_of_range, e.what());
  }
  trigger_->set_period(period);
  return {AckStatus::ok, AckReason::none};
}

FrameLoop::Verdict FrameLoop::set_exposure(const protocol::SetExposure& command) {
  using protocol::AckReason;
  using protocol::AckStatus;
  const hal::Nanoseconds exposure = exposure_of(command);
  const double gain = gain_of(command);
  const auto rejected = [&](AckReason reason, const std::string& why) {
    if (refusals_said_.allow(steady_now())) {
      journal(Priority::warning, "set_exposure %u us, %u cdB rejected: %s%s",
              static_cast<unsigned>(command.exposure_us),
              static_cast<unsigned>(command.gain_centidb), why.c_str(), left_out().c_str());
    }
    return Verdict{AckStatus::rejected, reason};
  };
  if (const std::string problem =
          frame_timing_problem(frame_period(), exposure, config_.cameras.timeout);
      !problem.empty()) {
    return rejected(AckReason::timing, problem);
  }
  hal::CameraSource& left = board_.left();
  hal::CameraSource& right = board_.right();
  const hal::Nanoseconds left_exposure = left.config().exposure;
  const double left_gain = left.config().gain;
  try {
    left.set_exposure(exposure, gain);
    try {
      right.set_exposure(exposure, gain);
    } catch (const Error&) {
      left.set_exposure(left_exposure, left_gain);  // both cameras alike, or neither changes
      throw;
    }
  } catch (const Error& e) {
    return rejected(AckReason::out_of_range, e.what());
  }
  return {AckStatus::ok, AckReason::none};
}

bool FrameLoop::odometry_runs() const {
  constexpr StageMask needs = protocol::stage_bit(protocol::Stage::odometry) |
                              protocol::stage_bit(protocol::Stage::sparse) |
                              protocol::stage_bit(protocol::Stage::corners);
  return (stages_ & pipeline_.available() & needs) == needs;
}

void FrameLoop::publish(const FrameResult& r, hal::Nanoseconds latency, bool trigger_from_capture) {
  if (r.calibration_health) last_calibration_health_ = r.calibration_health;
  if (r.drift) last_drift_ = r.drift;
  publish_link(r, latency, trigger_from_capture);
  // After the link's messages: the outputs' copies never delay what the robot steers by.
  if (outputs_ != nullptr) outputs_->publish(r, latency);
}

void FrameLoop::publish_link(const FrameResult& r, hal::Nanoseconds latency,
                             bool trigger_from_capture) {
  if (link_.protocol() == LinkProtocol::mavlink) {
    if (r.obstacles != nullptr) {
      link_.publish_obstacle_distance(
          obstacle_distance_message(*r.obstacles, r.trigger_ns, config_.obstacles));
    }
    // No pose yet, nothing to say: the autopilot's estimator waits for the first.
    if (r.odometry != nullptr && r.odometry->status != OdometryState::Status::starting) {
      link_.publish_odometry(mavlink_odometry(*r.odometry, r.trigger_ns));
    }
    return;
  }
  const PairMessages m = pair_messages(r, latency, trigger_from_capture);
  send(m.summary);
  if (m.detections) send(*m.detections);
  if (m.obstacles) send(*m.obstacles);
  if (m.depth_grid) send(*m.depth_grid);
  if (m.points) send(*m.points);
  for (const protocol::Message* message : m.stage_messages) {
    if (message != nullptr) send(*message);
  }
}

namespace {

// " (N not said since the last)", or nothing; no allocation.
struct LeftOut {
  char text[64] = "";
  LeftOut(std::uint64_t n, const char* what) {
    if (n > 0) {
      std::snprintf(text, sizeof text, " (%llu %s not said since the last)",
                    static_cast<unsigned long long>(n), what);
    }
  }
};

}  // namespace

// One journal line when a camera, the trigger line or the serial port goes, and one when it is
// back (health counts them); a device that comes and goes is said at most once in
// kDeviceLinesEvery.
void FrameLoop::say_device_changes() {
  const hal::Nanoseconds now = board_.clock().now();
  for (auto [camera, lost, lines] :
       {std::tuple{&board_.left_recovery(), &left_lost_, &device_lines_[0]},
        std::tuple{&board_.right_recovery(), &right_lost_, &device_lines_[1]}}) {
    if (camera->recovering() == *lost) continue;
    *lost = camera->recovering();
    if (*lost) {
      pipeline_.reset_history();
      if (lines->begins(now)) {
        journal(Priority::warning, "camera %s lost, reopening: %s%s", camera->name().c_str(),
                camera->last_error().c_str(), LeftOut(lines->left_out(), "losses").text);
      }
    } else if (lines->end_is_said()) {
      journal(Priority::info, "camera %s recovered", camera->name().c_str());
    }
  }
  // The firmware goes on without the trigger's edges while its line is not there.
  if (trigger_ && trigger_->line().available() == trigger_missing_) {
    trigger_missing_ = !trigger_missing_;
    const std::string& line = config_.trigger.line.line;
    if (trigger_missing_) {
      journal(Priority::warning, "trigger %s not there, waiting for it: %s", line.c_str(),
              trigger_->line().unavailable_reason().c_str());
    } else {
      journal(Priority::info, "trigger %s found", line.c_str());
    }
  }
  // A trigger that stopped firing (an autopilot that disarmed): said once, and once it is back.
  if (trigger_ && trigger_quiet() != trigger_quiet_) {
    trigger_quiet_ = !trigger_quiet_;
    const std::string& line = config_.trigger.line.line;
    JournalEpisodes& lines = device_lines_[2];
    if (trigger_quiet_ && lines.begins(now)) {
      journal(Priority::warning, "trigger %s: no edge for %lld ms, waiting for it%s", line.c_str(),
              std::llround(3e-6 * static_cast<double>(frame_period())),
              LeftOut(lines.left_out(), "pauses").text);
    } else if (!trigger_quiet_ && lines.end_is_said()) {
      journal(Priority::info, "trigger %s: edges again", line.c_str());
    }
  }
  // The delay from edge to frame, once learned (and again, when it changed).
  const hal::StereoPairer& pairer = grabber_.pairer();
  if (pairer.counters().delay_learned != delays_learned_ && pairer.edge_delay()) {
    delays_learned_ = pairer.counters().delay_learned;
    journal(Priority::info,
            "trigger %s: frames come %.3f ms after their edge (learned from %zu pairs)",
            config_.trigger.line.line.c_str(), static_cast<double>(*pairer.edge_delay()) / 1e6,
            hal::StereoPairer::kLearnPairs);
  }
  const hal::RecoveringSerialPort* serial = board_.serial_recovery();
  if (serial != nullptr && serial->connected() != serial_connected_) {
    serial_connected_ = !serial_connected_;
    const std::string& device = config_.serial.port.device;
    const std::string name = device.empty() ? board_.serial_peer() : device;  // on a change only
    JournalEpisodes& lines = device_lines_[3];
    if (!serial_connected_ && lines.begins(now)) {
      journal(Priority::warning, "serial port %s gone (hung up), waiting for it%s", name.c_str(),
              LeftOut(lines.left_out(), "hang-ups").text);
    } else if (serial_connected_ && lines.end_is_said()) {
      journal(Priority::info, "serial port %s open", name.c_str());
    }
  }
}

// Health once a second (a heartbeat on a MAVLink board), with the calibration's health after it.
void FrameLoop::publish_health() {
  std::optional<protocol::Health> h = health_.due(board_.clock().now(), faults());
  if (!h) return;
  ++summary_.health_messages;
  if (not_calibrated_) h->flags |= protocol::kHealthNotCalibrated;
  if (no_cascade_) h->flags |= protocol::kHealthNoCascade;
  if (corrections_said_ > 0) h->flags |= protocol::kHealthRigCorrected;
  if (trigger_quiet_) h->flags |= protocol::kHealthWaitingForTrigger;
  HealthReport report{*h, std::nullopt};
  if (last_calibration_health_ && last_calibration_health_->matches > 0) {
    report.calibration = calibration_health_message(*last_calibration_health_, last_drift_,
                                                    pipeline_.rig_correction());
  }
  if (outputs_ != nullptr) outputs_->publish_health(report);
  if (link_.protocol() == LinkProtocol::mavlink) {
    link_.publish_heartbeat(heartbeat_status());
    if (report.calibration) send_calibration_values(*report.calibration);
    return;
  }
  send(report.health);
  if (report.calibration) send(*report.calibration);
}

void FrameLoop::send_calibration_values(const protocol::CalibrationHealth& c) {
  // The board's clock is the system's monotonic one: time since the board booted.
  const auto ms =
      static_cast<std::uint32_t>(std::max<hal::Nanoseconds>(board_.clock().now(), 0) / 1'000'000);
  const auto value = [&](const char* name, double v) {
    link_.publish_named_value(name, static_cast<float>(v), ms);
  };
  value("rig_rows", c.median_offset_centipx / 100.0);
  value("rig_p90", c.p90_offset_centipx / 100.0);
  if ((c.flags & protocol::kDriftEstimated) != 0) {
    value("rig_pitch", c.pitch_mdeg / 1000.0);
    value("rig_roll", c.roll_mdeg / 1000.0);
    value("rig_sigma", std::max(c.pitch_sigma_mdeg, c.roll_sigma_mdeg) / 1000.0);
  }
  value("rig_corr", c.corrections);
  if (c.corrections > 0) {
    value("rig_cpitch", c.corrected_pitch_mdeg / 1000.0);
    value("rig_croll", c.corrected_roll_mdeg / 1000.0);
  }
}

void FrameLoop::tell_autopilot(mavlink::Severity severity, const char* format, ...) {
  if (link_.protocol() != LinkProtocol::mavlink) return;
  std::array<char, mavlink::kStatusTextSize + 1> text{};
  std::va_list values;
  va_start(values, format);
  const int n = std::vsnprintf(text.data(), text.size(), format, values);
  va_end(values);
  if (n < 0) return;
  link_.publish_status_text(
      severity, std::string_view(text.data(), std::min<std::size_t>(n, text.size() - 1)));
}

// A board whose baud rate carries its summaries (the board file's check) but not every point
// and depth grid at its rate drops those, counted in health: said once, not every pair.
void FrameLoop::say_link_capacity() {
  const std::uint64_t over_budget = link_.counters().over_budget;
  const hal::Nanoseconds now = board_.clock().now();
  if (over_budget != over_budget_seen_) {
    over_budget_seen_ = over_budget;
    over_budget_at_ = now;
    if (!link_over_budget_) {
      link_over_budget_ = true;
      journal(Priority::warning,
              "serial link: %d baud cannot carry every message at %.1f pairs/s; those over its "
              "budget are dropped (health counts them in messages_dropped)",
              config_.serial.port.baud, 1e9 / static_cast<double>(frame_period()));
    }
  } else if (link_over_budget_ && now - over_budget_at_ >= kLinkFitsAgain) {
    link_over_budget_ = false;
    journal(Priority::info, "serial link: every message fits again (%llu dropped over budget)",
            static_cast<unsigned long long>(over_budget));
  }
}

// Between pairs: health, the journal's device lines, the service watchdog (pinged only while
// the link's thread goes round too).
void FrameLoop::tick() {
  publish_health();
  say_device_changes();
  say_link_capacity();
  // A snapshot no pair came for (the cameras went, or the trigger stopped, after it was asked
  // for) is answered within a bound.
  if (snapshot_pending_ && board_.clock().now() - snapshot_asked_at_ > kSnapshotWait) {
    snapshot_pending_ = false;
    conclude(snapshot_sequence_, {protocol::AckStatus::rejected, protocol::AckReason::no_pairs});
  }
  if (heartbeat_ && link_.alive(kLinkAlive)) heartbeat_();
}

std::optional<NextPair::Images> FrameLoop::GrabAhead::take() {
  struct DeferReopen {
    hal::RecoveringCamera& left;
    hal::RecoveringCamera& right;
    DeferReopen(hal::RecoveringCamera& l, hal::RecoveringCamera& r) : left(l), right(r) {
      left.defer_reopen(true);
      right.defer_reopen(true);
    }
    ~DeferReopen() {
      left.defer_reopen(false);
      right.defer_reopen(false);
    }
  };
  // With two buffers a camera has none left while two pairs are held: the next one is taken
  // when the current one is done.
  if (loop_.board_.left().config().buffer_count < 3 ||
      loop_.board_.right().config().buffer_count < 3) {
    return std::nullopt;
  }
  const DeferReopen defer(loop_.board_.left_recovery(), loop_.board_.right_recovery());
  const hal::PairResult got = loop_.grabber_.next(0);
  if (got.status == hal::PairStatus::timeout) return std::nullopt;
  result = got;
  if (got.status != hal::PairStatus::ok) return std::nullopt;
  return Images{got.pair.left.gray, got.pair.right.gray, got.pair.left.sequence};
}

// The pair taken ahead while the one before was processed (or the camera it found lost), else
// the next one from the cameras.
hal::PairResult FrameLoop::next_pair() {
  if (ahead_.result) {
    const hal::PairResult got = *ahead_.result;
    ahead_.result.reset();
    return got;
  }
  return grabber_.next(config_.cameras.timeout);
}

// The freshest pair from what the grabber gave: older ones that waited behind it are skipped (and
// counted stale). False when there is none to process: a timeout, a camera lost (its reopen
// unmapped the buffers a held pair's frames are in: that pair goes too).
bool FrameLoop::take_freshest(hal::PairResult& got) {
  if (got.status == hal::PairStatus::timeout) {
    ++summary_.timeouts;
    return false;
  }
  if (got.status == hal::PairStatus::device_lost) {
    grabber_.pairer().reset(got.lost_side);
    pipeline_.drop_pair_ahead();
    return false;
  }
  const auto skip = [&] {
    grabber_.pairer().ledger().stale(got.pair.left.sequence);
    grabber_.release(got.pair);
    pipeline_.drop_pair_ahead();  // it may be the pair taken ahead
    ++summary_.stale;
  };
  for (;;) {
    hal::PairResult newer = grabber_.next(0);
    if (newer.status == hal::PairStatus::device_lost) {
      skip();
      return false;
    }
    if (newer.status != hal::PairStatus::ok) return true;
    skip();
    got = newer;
  }
}

// The pair's trigger edge (hal/stereo_pairing.hpp: every pair has one when the board has a
// trigger); the left frame's time otherwise.
FrameLoop::TriggerTime FrameLoop::trigger_time(const hal::StereoPair& pair) const {
  if (pair.edge && pair.edge->clock == board_.clock().id()) return {pair.edge->timestamp, false};
  return {pair.left.timestamp, true};
}

void FrameLoop::process_pair(const hal::StereoPair& pair) {
  hal::Clock& clock = board_.clock();
  const TriggerTime trigger = trigger_time(pair);
  const hal::Nanoseconds captured = clock.now() - trigger.ns;
  // How long the pair waited for the loop: since the later of its two frames (0 when their
  // timestamps are on another clock than the board's).
  const bool same_clock = pair.left.clock == clock.id() && pair.right.clock == clock.id();
  const hal::Nanoseconds waited =
      same_clock ? clock.now() - std::max(pair.left.timestamp, pair.right.timestamp) : 0;
  // Settled as published before the next pair is looked for while this one is processed: the
  // ledger's window follows the newest frame seen, and with a loop far behind the trigger it
  // would otherwise settle this pair as dropped first. No health message goes out before its
  // summary.
  grabber_.pairer().ledger().published(pair.left.sequence);
  const hal::Nanoseconds t0 = steady_now();
  const FrameResult& r = pipeline_.process(pair.left.gray, pair.right.gray, pair.left.sequence,
                                           trigger.ns, stages_, &ahead_);
  const hal::Nanoseconds t1 = steady_now();
  publish(r, clock.now() - trigger.ns, trigger.from_capture);
  follow_correction(r);
  const hal::Nanoseconds t2 = steady_now();
  StageTimes times = r.times;
  times[static_cast<std::size_t>(Stage::capture)] = captured;
  times[static_cast<std::size_t>(Stage::publish)] = t2 - t1;
  times[static_cast<std::size_t>(Stage::total)] = t2 - t0;
  health_.record(clock.now() - trigger.ns, times, waited);
  if (snapshot_pending_) {
    snapshot_pending_ = false;
    if (!snapshots_.take(r, snapshot_sequence_)) {  // the disk filled meanwhile
      conclude(snapshot_sequence_, {protocol::AckStatus::rejected, protocol::AckReason::storage});
    }
  }
  if (observer_ != nullptr) observer_->on_frame(r);
  ++summary_.frames;
}

// recalibrate: a correction from the drift's window now, whatever online_correction says.
FrameLoop::Verdict FrameLoop::recalibrate(std::uint16_t sequence) {
  using protocol::AckReason;
  using protocol::AckStatus;
  using Outcome = RigCorrection::Outcome;
  RigCorrection* correction = pipeline_.rig_correction();
  if (correction == nullptr) return {AckStatus::unsupported, AckReason::none};
  if (recalibrate_pending_) return {AckStatus::rejected, AckReason::busy};
  const Outcome outcome = correction->correct(last_drift_.value_or(calib::DriftEstimate{}));
  switch (outcome) {
    case Outcome::started:
      recalibrate_pending_ = true;
      recalibrate_sequence_ = sequence;
      journal(Priority::notice,
              "recalibrate: the right camera turned %+.3f degrees of pitch and %+.3f of roll "
              "(rows %.2f px off): rebuilding its map",
              degrees(last_drift_->pitch), degrees(last_drift_->roll),
              last_drift_->median_offset_px);
      return {AckStatus::ok, AckReason::none};
    case Outcome::nothing_to_correct:
      return {AckStatus::ok, AckReason::none};  // the rig holds: nothing to do
    case Outcome::busy:
      return {AckStatus::rejected, AckReason::busy};
    case Outcome::no_estimate:
      return {AckStatus::rejected, AckReason::no_pairs};
    case Outcome::out_of_range:
      return {AckStatus::rejected, AckReason::out_of_range};
    default:  // would_not_lower
      return {AckStatus::rejected, AckReason::failed};
  }
}

// save_calibration: the rig in use written beside the board's calibration file by the maps'
// thread.
FrameLoop::Verdict FrameLoop::save_calibration(std::uint16_t sequence) {
  using protocol::AckReason;
  using protocol::AckStatus;
  RigCorrection* correction = pipeline_.rig_correction();
  if (correction == nullptr || correction->corrected_file().empty()) {
    return {AckStatus::unsupported, AckReason::none};
  }
  if (save_pending_ || !correction->request_save()) return {AckStatus::rejected, AckReason::busy};
  save_pending_ = true;
  save_sequence_ = sequence;
  return {AckStatus::ok, AckReason::none};
}

void FrameLoop::answer_corrections(bool stopping) {
  RigCorrection* correction = pipeline_.rig_correction();
  if (correction == nullptr) return;
  if (save_pending_) {
    if (const std::optional<bool> saved = correction->saved()) {
      save_pending_ = false;
      if (*saved) {
        journal(Priority::notice, "save_calibration: %s written",
                correction->corrected_file().c_str());
        conclude(save_sequence_, {protocol::AckStatus::ok, protocol::AckReason::none});
      } else {
        journal(Priority::warning, "save_calibration: %s", correction->save_error().c_str());
        conclude(save_sequence_, {protocol::AckStatus::rejected, protocol::AckReason::storage});
      }
    }
  }
  if (!stopping) return;  // a correction in place is answered by follow_correction()
  const Verdict failed{protocol::AckStatus::rejected, protocol::AckReason::failed};
  if (save_pending_) {
    save_pending_ = false;
    conclude(save_sequence_, failed);
  }
  if (recalibrate_pending_) {
    recalibrate_pending_ = false;
    const bool in_place = correction->corrections() != corrections_said_;
    conclude(recalibrate_sequence_,
             in_place ? Verdict{protocol::AckStatus::ok, protocol::AckReason::none} : failed);
  }
}

// The rig corrected while running: each correction said when it starts and once it is in
// place; the window's estimate considered (calibration_health.online_correction), a refusal
// said when its reason is new.
void FrameLoop::follow_correction(const FrameResult& r) {
  using Outcome = RigCorrection::Outcome;
  RigCorrection* correction = pipeline_.rig_correction();
  if (correction == nullptr) return;
  if (correction->corrections() != corrections_said_) {
    corrections_said_ = correction->corrections();
    // The estimate was of the rig before: a recalibrate must not undo the same turn again.
    last_drift_.reset();
    last_outcome_ = Outcome::none;
    const calib::CameraTurn total = correction->total();
    journal(Priority::notice,
            "calibration: corrected (%d): the right camera's map rebuilt; the rig is now %+.3f "
            "degrees of pitch and %+.3f of roll from its file",
            corrections_said_, degrees(total.pitch), degrees(total.roll));
    tell_autopilot(mavlink::Severity::notice, "epipole: rig corrected, pitch %+.3f roll %+.3f",
                   degrees(total.pitch), degrees(total.roll));
    if (recalibrate_pending_) {
      recalibrate_pending_ = false;
      conclude(recalibrate_sequence_, {protocol::AckStatus::ok, protocol::AckReason::none});
    }
  }
  if (!r.drift) return;
  const Outcome outcome = correction->consider(*r.drift);
  // A refusal is said once until a correction is made (rows hovering about min_offset_px would
  // otherwise say it again at every crossing).
  if (outcome == Outcome::none || outcome == Outcome::busy || outcome == Outcome::no_estimate ||
      outcome == Outcome::nothing_to_correct || outcome == last_outcome_) {
    return;
  }
  last_outcome_ = outcome;
  const calib::DriftEstimate& e = *r.drift;
  switch (outcome) {
    case Outcome::started:
      journal(Priority::notice,
              "calibration: the right camera turned %+.3f degrees of pitch and %+.3f of roll "
              "(rows %.2f px off, %.2f px once undone): rebuilding its map",
              degrees(e.pitch), degrees(e.roll), e.median_offset_px, e.median_corrected_px);
      break;
    case Outcome::would_not_lower:
      journal(Priority::warning,
              "calibration: rows %.2f px off, but undoing the estimated turn (%+.3f, %+.3f "
              "degrees) would leave %.2f px: not corrected",
              e.median_offset_px, degrees(e.pitch), degrees(e.roll), e.median_corrected_px);
      tell_autopilot(mavlink::Severity::warning, "epipole: rows %.2f px off, not correctable",
                     e.median_offset_px);
      break;
    case Outcome::out_of_range:
      journal(Priority::warning,
              "calibration: the right camera turned %+.3f degrees of pitch and %+.3f of roll, "
              "beyond calibration_health.max_correction_deg from its file: not corrected "
              "(calibrate the rig again)",
              degrees(e.pitch), degrees(e.roll));
      tell_autopilot(mavlink::Severity::warning, "epipole: rig turned past its bound: calibrate");
      break;
    default:
      break;
  }
}

void FrameLoop::add_memory(MemoryReport& report) const {
  report.add("frame loop", sizeof(FrameLoop) + (trigger_ ? sizeof(TriggerWatch) : 0) +
                               health_.working_set_bytes());
  if (snapshots_.enabled()) report.add("snapshots", snapshots_.working_set_bytes());
  if (outputs_ != nullptr) outputs_->add_memory(report);
}

RunSummary FrameLoop::run(std::uint64_t max_frames, const std::atomic<bool>& stop) {
  start();  // the cameras (libcamera's threads), the trigger's and the link's threads first
  const ScopedThreadRole compute(ThreadRole::compute);
  while (!stop.load(std::memory_order_relaxed) &&
         (max_frames == 0 || summary_.frames < max_frames)) {
    apply_commands();
    answer_snapshots();
    answer_corrections(/*stopping=*/false);
    hal::PairResult got = next_pair();
    tick();  // before the new pair is recorded: the health window that ended holds those before
    if (!take_freshest(got)) continue;
    process_pair(got.pair);
    grabber_.release(got.pair);
  }
  finish();
  summary_.rectified_ahead = pipeline_.pairs_rectified_ahead();
  summary_.used_ahead = pipeline_.pairs_used_ahead();
  summary_.pairing = grabber_.pairer().counters();
  summary_.faults = faults();
  summary_.link = link_.counters();
  if (outputs_ != nullptr) summary_.outputs = outputs_->reports();
  summary_.stages = stages_;
  return summary_;
}

}  // namespace epipole::firmware
