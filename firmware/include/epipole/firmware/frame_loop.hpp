#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include "epipole/firmware/board.hpp"
#include "epipole/firmware/board_config.hpp"
#include "epipole/firmware/command_memory.hpp"
#include "epipole/firmware/health_monitor.hpp"
#include "epipole/firmware/journal.hpp"
#include "epipole/firmware/link.hpp"
#include "epipole/firmware/memory_report.hpp"
#include "epipole/firmware/outputs.hpp"
#include "epipole/firmware/pipeline.hpp"
#include "epipole/firmware/snapshot.hpp"
#include "epipole/firmware/trigger_watch.hpp"
#include "epipole/hal/stereo_pairing.hpp"

namespace epipole::firmware {

// Sees every processed frame pair (the host tool's pictures, tests). Called on the frame loop's
// thread before the pair's buffers go back to the cameras; whatever it keeps must be copied.
class FrameObserver {
 public:
  virtual ~FrameObserver() = default;
  virtual void on_frame(const FrameResult& result) = 0;
  // Every message the firmware published (after it was queued for the link).
  virtual void on_message(const protocol::Message&) {}
};

// What a run did, for its last log line and for tests.
struct RunSummary {
  std::uint64_t frames = 0;    // pairs processed
  std::uint64_t stale = 0;     // pairs skipped because a newer one was already there
  std::uint64_t timeouts = 0;  // waits for a pair that timed out
  // Pairs that came while the one before was processed, taken and rectified then (in the
  // workers' last gaps), and of those the ones processed (the others were stale by then).
  std::uint64_t rectified_ahead = 0;
  std::uint64_t used_ahead = 0;
  std::uint64_t health_messages = 0;
  std::vector<OutputReport> outputs;  // what each output did
  std::uint64_t commands = 0;
  std::uint64_t resent_commands = 0;  // resends of commands applied before: answered, not applied
  hal::PairingCounters pairing;
  FaultCounts faults;
  LinkCounters link;
  StageMask stages = 0;  // the stages enabled at the end
};

// How the frame loop pairs the board's frames: by time, each pair then taking the trigger edge
// at its time, the delay from edge to frame being the board file's pairing.edge_delay_us, or
// else the cameras' own (hal::CameraSource::edge_delay()), or else learned from the first pairs;
// without a trigger (trigger.backend none: free-running cameras) by time alone, the tolerance
// checked against the cameras' frame period.
hal::PairingConfig pairing_config(const BoardConfig& config,
                                  std::optional<hal::Nanoseconds> camera_edge_delay = std::nullopt);

// The firmware's frame loop: trigger -> capture pair -> rectify -> corners -> dense stereo ->
// obstacles -> publish, with health once a second and the robot's commands applied between
// pairs. Everything it needs is allocated by its constructor (and those of its parts): run()
// never allocates.
class FrameLoop {
 public:
  // `outputs`: where each pair goes besides the link (none: nowhere else).
  FrameLoop(const BoardConfig& config, Board& board, Pipeline& pipeline, Link& link,
            Outputs* outputs = nullptr);
  ~FrameLoop();
  FrameLoop(const FrameLoop&) = delete;
  FrameLoop& operator=(const FrameLoop&) = delete;

  void set_observer(FrameObserver* observer) { observer_ = observer; }
  // Called after each pair and each wait (the service watchdog).
  void set_heartbeat(std::function<void()> heartbeat) { heartbeat_ = std::move(heartbeat); }

  // Runs until `stop` is set or `max_frames` pairs (0: no limit) were processed. Returns within
  // the cameras' timeout of `stop` being set, with the link drained of what it was writing.
  RunSummary run(std::uint64_t max_frames, const std::atomic<bool>& stop);

  // Its own buffers (itself with the pairer's queues, health's latencies, the snapshots' copies).
  void add_memory(MemoryReport& report) const;

 private:
  void start();
  void finish();
  using Verdict = CommandVerdict;
  void apply_commands();
  void answer(std::uint16_t sequence, Verdict verdict);
  void conclude(std::uint16_t sequence, Verdict verdict);
  std::string left_out() const;
  Verdict set_trigger_rate(const protocol::SetTriggerRate& command);
  Verdict set_exposure(const protocol::SetExposure& command);
  Verdict request_snapshot(std::uint16_t sequence);
  void answer_snapshots();
  Verdict recalibrate(std::uint16_t sequence);
  Verdict save_calibration(std::uint16_t sequence);
  // The recalibrate and save_calibration commands answered once done (or at the stop: failed).
  void answer_corrections(bool stopping);
  hal::Nanoseconds frame_period() const;
  // trigger_from_capture: result.trigger_ns is the left frame's time, not a trigger edge's.
  void publish(const FrameResult& result, hal::Nanoseconds latency, bool trigger_from_capture);
  void follow_correction(const FrameResult& result);
  void publish_link(const FrameResult& result, hal::Nanoseconds latency, bool trigger_from_capture);
  void send(const protocol::Message& message);
  // The steps of run().
  void tick();
  void publish_health();
  // MAVLink: the calibration's figures as NAMED_VALUE_FLOATs (docs/protocol.md), and an event
  // of the rig's correction as a STATUSTEXT (`format` printf-like, cut at 50 characters).
  void send_calibration_values(const protocol::CalibrationHealth& calibration);
  [[gnu::format(printf, 3, 4)]] void tell_autopilot(mavlink::Severity severity, const char* format,
                                                    ...);
  void say_device_changes();
  void say_link_capacity();
  bool trigger_quiet() const;
  // The odometry runs on the pairs (and goes out on the link): the link's capacity counts it.
  bool odometry_runs() const;
  hal::PairResult next_pair();
  bool take_freshest(hal::PairResult& got);
  struct TriggerTime {
    hal::Nanoseconds ns;
    bool from_capture;  // the left frame's time: no trigger edge was recorded for the pair
  };
  TriggerTime trigger_time(const hal::StereoPair& pair) const;
  void process_pair(const hal::StereoPair& pair);
  FaultCounts faults();
  // MAVLink's system status: calibrating (not ready) until the rig has its calibration.
  std::uint8_t heartbeat_status() const {
    return not_calibrated_ ? mavlink::kMavStateCalibrating : mavlink::kMavStateActive;
  }

  // The pair after the one in process, when it came meanwhile (the pipeline's NextPair): taken
  // on one of the pipeline's workers, with the cameras' reopening deferred, since the current
  // pair's frames may still be read.
  class GrabAhead final : public NextPair {
   public:
    explicit GrabAhead(FrameLoop& loop) : loop_(loop) {}
    std::optional<Images> take() override;
    std::optional<hal::PairResult> result;  // what take() got: a pair, or a camera lost

   private:
    FrameLoop& loop_;
  };

  const BoardConfig& config_;
  Board& board_;
  Pipeline& pipeline_;
  Link& link_;
  Outputs* outputs_;
  std::unique_ptr<TriggerWatch> trigger_;  // before grabber_, which checks pairs against it
  hal::StereoGrabber grabber_;
  HealthMonitor health_;
  SnapshotWriter snapshots_;
  StageMask stages_;
  bool not_calibrated_;  // the board's calibration file does not exist yet
  bool no_cascade_;      // nor its compiled cascade, with detection on
  GrabAhead ahead_{*this};
  FrameObserver* observer_ = nullptr;
  std::function<void()> heartbeat_;
  RunSummary summary_;
  bool started_ = false;
  CommandMemory commands_;  // each command applied once (retries, reboots: protocol.md)
  JournalLimit refusals_said_{1'000'000'000};  // refused commands: a journal line a second
  bool snapshot_pending_ = false;
  std::uint16_t snapshot_sequence_ = 0;
  bool recalibrate_pending_ = false;  // answered once the corrected map is in place
  std::uint16_t recalibrate_sequence_ = 0;
  bool save_pending_ = false;  // answered once the file is written
  std::uint16_t save_sequence_ = 0;
  hal::Nanoseconds snapshot_asked_at_ = 0;
  // How long a snapshot asked for waits for a pair before it is refused (no_pairs).
  static constexpr hal::Nanoseconds kSnapshotWait = 2'000'000'000;
  std::uint64_t rejected_commands_ = 0;
  // What the journal was last told of the devices.
  bool left_lost_ = false;
  bool right_lost_ = false;
  bool trigger_missing_ = false;
  std::uint64_t delays_learned_ = 0;
  bool trigger_quiet_ = false;       // said in the journal, and in health's flags
  hal::Nanoseconds started_at_ = 0;  // the pairer's, as last said in the journal
  bool serial_connected_ = true;
  // The lines of the left and right camera, the trigger's pauses and the serial port.
  static constexpr hal::Nanoseconds kDeviceLinesEvery = 10'000'000'000;
  std::array<JournalEpisodes, 4> device_lines_{
      JournalEpisodes(kDeviceLinesEvery), JournalEpisodes(kDeviceLinesEvery),
      JournalEpisodes(kDeviceLinesEvery), JournalEpisodes(kDeviceLinesEvery)};
  // Messages the baud rate cannot carry: said when they start being dropped, and once every
  // message fitted for kLinkFitsAgain.
  bool link_over_budget_ = false;
  std::uint64_t over_budget_seen_ = 0;
  hal::Nanoseconds over_budget_at_ = 0;
  static constexpr hal::Nanoseconds kLinkFitsAgain = 10'000'000'000;
  std::optional<calib::HealthFigure> last_calibration_health_;  // of the latest matches
  std::optional<calib::DriftEstimate> last_drift_;
  int corrections_said_ = 0;  // the rig's corrections the journal has told of
  RigCorrection::Outcome last_outcome_ = RigCorrection::Outcome::none;
};

}  // namespace epipole::firmware
