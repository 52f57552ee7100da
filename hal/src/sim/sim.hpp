#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "epipole/core/image.hpp"
#include "epipole/hal/backend_settings.hpp"
#include "epipole/hal/camera.hpp"
#include "epipole/hal/clock.hpp"
#include "epipole/hal/hardware.hpp"
#include "epipole/hal/side.hpp"
#include "epipole/hal/trigger.hpp"
#include "sim/sim_files.hpp"

namespace epipole::hal {

class SimCamera;

// The simulated board's trigger master: edges every 1/rate_hz on a VirtualClock, from the
// time of start(). Edges are generated lazily, as the clock passes them: wait_edge() sleeps
// (jumps) to the next one, and a camera's acquire() asks for all edges up to its deadline. Every
// edge reaches every connected camera exactly once. set_rate() re-anchors the schedule at the
// last edge generated (given to a camera, reported or recorded) or passed by the clock: the
// edges after it come at the new period.
// A glitch of the simulated trigger line, at edge `sequence` of its schedule.
enum class SimTriggerGlitchKind {
  extra_edge,  // the record also gets an edge `duration` after it (a bounce, or a spurious
               // pulse the cameras ignore, busy exposing or reading out)
  unrecorded,  // the cameras fire, but the record never gets the edge (a slave missed it)
  late,        // the edge fires `duration` late, for the cameras and the record (a master that
               // woke late); later edges keep their schedule
  pause,       // no edge fires from it for `duration` (an autopilot that disarmed): neither the
               // cameras nor the record get one; then the schedule goes on
};

struct SimTriggerGlitch {
  SimTriggerGlitchKind kind = SimTriggerGlitchKind::extra_edge;
  std::uint32_t sequence = 0;
  Nanoseconds duration = 0;
};

class SimTrigger final : public TriggerLine {
 public:
  SimTrigger(TriggerConfig config, VirtualClock& clock);
  const TriggerConfig& config() const override { return config_; }
  void start() override;
  void stop() override;
  EdgeResult wait_edge(Nanoseconds timeout) override;
  void set_rate(double rate_hz) override;

  // Connects a camera (at most 4); it is told of every edge from then on.
  void connect(SimCamera& camera);
  // Every edge is also added to `record` (nullptr: none), as the firmware's trigger thread
  // records the edges of a real line.
  bool record_edges_to(TriggerRecord* record) override {
    record_ = record;
    return true;
  }
  // Emits every edge with timestamp <= until to the connected cameras.
  void emit_until(Nanoseconds until);
  // A glitch of the line (set up before the edges it names are emitted).
  void inject(const SimTriggerGlitch& glitch) { glitches_.push_back(glitch); }
  // When edge `sequence` of the schedule fired (its glitches included): the truth for tests.
  Nanoseconds edge_time(std::uint32_t sequence) const { return edge(sequence).timestamp; }
  Nanoseconds period() const { return period_; }
  bool running() const { return running_; }

 private:
  // Edge n of the schedule, on the virtual clock.
  TriggerEdge edge(std::uint32_t sequence) const;
  const SimTriggerGlitch* glitch(SimTriggerGlitchKind kind, std::uint32_t sequence) const;
  bool fires(std::uint32_t sequence) const;  // not in a pause
  void record(const TriggerEdge& edge);
  TriggerConfig config_;
  VirtualClock& clock_;
  Nanoseconds period_;
  EdgeSchedule schedule_;
  bool running_ = false;
  std::uint32_t next_emit_ = 0;    // the next edge to give the cameras
  std::uint32_t next_report_ = 0;  // the next edge wait_edge() reports
  std::uint32_t next_record_ = 0;  // the next edge added to the record
  SimCamera* cameras_[4] = {};
  int camera_count_ = 0;
  TriggerRecord* record_ = nullptr;
  std::vector<SimTriggerGlitch> glitches_;
  std::optional<TriggerEdge> extra_;  // an extra edge to record once the clock passes it
};

// A fault injected into one simulated camera, keyed by trigger sequence.
enum class SimFaultKind {
  drop,            // the frames of `count` triggers from `sequence` never arrive
  delay,           // the frame arrives `duration` late (and with it those queued behind it)
  stall,           // nothing arrives for `duration` from trigger `sequence`: frames then are lost
  disconnect,      // from trigger `sequence`: device_lost until reopen(); `value` reopens fail
  corrupt_pixels,  // the frame's pixels are garbage (nothing tells: like a bad sensor link)
  damaged,         // the driver flags the frame damaged: acquire() reports corrupt, no frame
  wrong_sequence,  // the frame reports sequence `value` instead of its own
  skew,            // the frame's timestamp is off by `duration` (may be negative)
  broken,          // from trigger `sequence`, for `duration`: the device opens, but every
                   // acquire() reports device_lost (a driver failing every dequeue with EIO)
};

struct SimFault {
  SimFaultKind kind = SimFaultKind::drop;
  std::uint32_t sequence = 0;
  std::uint32_t count = 1;
  Nanoseconds duration = 0;
  std::uint32_t value = 0;
};

// Random faults, decided per trigger sequence from a seed (deterministic, independent per
// camera when the seeds differ). Probabilities per frame.
struct SimFaultRates {
  double drop = 0.0;
  double corrupt_pixels = 0.0;
  double damaged = 0.0;
  double wrong_sequence = 0.0;  // reports a neighbour's sequence (duplicate or skip)
  double delay = 0.0;           // by up to max_delay
  Nanoseconds max_delay = 0;
  std::uint64_t seed = 1;
};

struct SimCameraTiming {
  Nanoseconds exposure_delay = 5'000'000;  // frame timestamp = edge + this + jitter
  Nanoseconds jitter = 0;                  // uniform in [-jitter, +jitter]
  Nanoseconds readout = 2'000'000;         // the frame is delivered at timestamp + readout
  std::uint64_t seed = 7;
};

// A simulated camera on the virtual clock, replaying in-memory images (frame n shows image
// n % count). Each trigger edge makes it deliver one frame whose sequence is the trigger
// sequence. All memory is taken at construction: the frame buffers (config.buffer_count
// images) and the queue of pending triggers; acquire() and release() never allocate. In
// free-running mode without a connected trigger it triggers itself at config.fps.
class SimCamera final : public CameraSource {
 public:
  SimCamera(CameraConfig config, std::shared_ptr<const std::vector<GrayImage>> images,
            VirtualClock& clock, SimCameraTiming timing = {});

  const std::string& name() const override { return name_; }
  const CameraConfig& config() const override { return config_; }
  void start() override;
  void stop() override;
  bool streaming() const override { return streaming_; }
  AcquireResult acquire(Nanoseconds timeout) override;
  void release(const Frame& frame) override;
  void reopen() override;
  // Stores them; a frame's brightness is scaled by exposure x gain relative to the configured
  // values (each where both it and the configured one are not automatic), saturating at 255.
  void set_exposure(Nanoseconds exposure, double gain) override;
  std::optional<Nanoseconds> edge_delay() const override { return timing_.exposure_delay; }
  // A frame can start once the one before is read out.
  std::optional<Nanoseconds> shortest_frame_period() const override { return timing_.readout; }
  std::size_t working_set_bytes() const override;

  void inject(const SimFault& fault);
  void set_fault_rates(const SimFaultRates& rates) { rates_ = rates; }
  // The trigger a held frame really belongs to (ground truth for tests).
  std::uint32_t true_sequence(const Frame& frame) const;
  // Frames lost because the pending queue was full (the consumer was too slow).
  std::uint64_t overruns() const { return overruns_; }
  std::uint64_t delivered() const { return delivered_; }

  // Called by SimTrigger for every edge.
  void on_trigger(const TriggerEdge& edge);

 private:
  friend class SimTrigger;
  struct Pending {
    std::uint32_t true_sequence = 0;
    std::uint32_t reported_sequence = 0;
    Nanoseconds timestamp = 0;
    Nanoseconds ready = 0;
    bool corrupt = false;
    bool damaged = false;
    bool disconnect = false;
    bool broken = false;
  };
  const SimFault* find_fault(SimFaultKind kind, std::uint32_t sequence) const;
  void pull_edges(Nanoseconds until);

  CameraConfig config_;
  Nanoseconds configured_exposure_;
  double configured_gain_;
  std::uint32_t brightness_q16_ = 1u << 16;  // the scale of the replayed pixels
  std::string name_;
  std::shared_ptr<const std::vector<GrayImage>> images_;
  VirtualClock& clock_;
  SimCameraTiming timing_;
  SimTrigger* trigger_ = nullptr;
  SimTrigger own_trigger_;  // free running without a board trigger
  std::vector<SimFault> faults_;
  SimFaultRates rates_;

  std::vector<GrayImage> buffers_;
  std::vector<std::uint8_t> held_;
  std::vector<std::uint32_t> buffer_truth_;
  std::vector<Pending> queue_;  // a ring of fixed capacity
  std::size_t queue_head_ = 0;
  std::size_t queue_size_ = 0;

  bool streaming_ = false;
  bool disconnected_ = false;
  std::uint32_t failing_reopens_ = 0;
  Nanoseconds stalled_until_ = 0;
  Nanoseconds broken_until_ = 0;
  std::uint32_t generation_ = 0;
  std::uint64_t overruns_ = 0;
  std::uint64_t delivered_ = 0;
};

// The simulated board: a virtual clock, the trigger master and the images of the left and
// right cameras. The registry's "sim" backends create cameras ("left", "right") on it; it is
// what they share on a hal::Hardware, made from the board file's `sim:` section.
struct SimBoard final : BackendBoard {
  // The trigger at rate_hz, its pulses a quarter period long.
  SimBoard(double rate_hz, std::vector<GrayImage> left_images, std::vector<GrayImage> right_images,
           SimCameraTiming camera_timing = {});
  // The trigger as configured (the board file's rate and pulse width; a master).
  SimBoard(TriggerConfig trigger_config, std::vector<GrayImage> left_images,
           std::vector<GrayImage> right_images, SimCameraTiming camera_timing = {});
  // The trigger as configured, replaying images it shares with whoever gave them.
  SimBoard(TriggerConfig trigger_config, const std::shared_ptr<const StereoImages>& images,
           SimCameraTiming camera_timing = {});
  VirtualClock clock;
  SimTrigger trigger;
  std::shared_ptr<const std::vector<GrayImage>> left;
  std::shared_ptr<const std::vector<GrayImage>> right;
  SimCameraTiming timing;
  SimFaultRates fault_rates;  // of the cameras the "sim" backend makes (seeded per side)
  // The cameras the "sim" backend made on this board (null until it did), for fault injection.
  SimCamera* camera(Side side) const { return cameras[index(side)]; }
  std::array<SimCamera*, 2> cameras{};

  Clock* own_clock() override { return &clock; }
  std::size_t memory_bytes() const override;  // the scene's images
  std::size_t scene_images() const { return left->size(); }
};

// The simulated board of a Hardware whose cameras are simulated, else null (for the tests and
// host tools that drive the simulation).
SimBoard* simulated_board(const Hardware& hardware);

}  // namespace epipole::hal
