#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>

#include "epipole/hal/camera.hpp"
#include "epipole/hal/clock.hpp"
#include "epipole/hal/side.hpp"
#include "epipole/hal/trigger.hpp"
#include "epipole/hal/trigger_ledger.hpp"

namespace epipole::hal {

struct StereoPair {
  Frame left;
  Frame right;
  // The trigger edge both frames were exposed on (with a trigger record); its number is the
  // pair's (both frames' `sequence`).
  std::optional<TriggerEdge> edge;
};

// Everything the pairer did with the frames of one side.
// pushed = paired + unpaired + mismatched + out_of_order + off_trigger + (frames still waiting).
struct PairingSideCounters {
  std::uint64_t pushed = 0;
  // No frame of the other side lay within the tolerance (the other side lost it).
  std::uint64_t unpaired = 0;
  // The frame and its partner are on different clocks.
  std::uint64_t mismatched = 0;
  // Its timestamp did not increase on its side (free running: or its sequence); with a trigger
  // record, also a pair on an edge an earlier pair already had.
  std::uint64_t out_of_order = 0;
  // With a trigger record: no edge at the pair's time (a missed edge), so the pair is dropped.
  std::uint64_t off_trigger = 0;
  // Damaged frames the cameras reported (AcquireStatus::corrupt); never pushed (StereoGrabber).
  std::uint64_t corrupt = 0;
};

struct PairingCounters {
  std::uint64_t pairs = 0;
  std::array<PairingSideCounters, 2> sides{};  // by Side
  // With a trigger record: the times the edge delay was learned (again: after kRelearnAfter
  // pairs in a row with no edge at their time, the delay is taken to have changed).
  std::uint64_t delay_learned = 0;
  PairingSideCounters& of(Side side) { return sides[index(side)]; }
  const PairingSideCounters& of(Side side) const { return sides[index(side)]; }
  PairingSideCounters& left() { return sides[0]; }
  PairingSideCounters& right() { return sides[1]; }
  const PairingSideCounters& left() const { return sides[0]; }
  const PairingSideCounters& right() const { return sides[1]; }
};

struct PairingConfig {
  Nanoseconds tolerance = 2'000'000;  // |t_left - t_right| allowed for one trigger
  // The trigger period (free running: the cameras' frame period), when known: the tolerance
  // (and the edge tolerance) must be below half of it, so that frames of neighbouring triggers
  // can never pass a timestamp check. 0: not checked. With a trigger record and no edge delay it
  // is needed (the delay is learned within one period).
  Nanoseconds trigger_period = 0;
  // With a trigger record: the board's frame timestamp minus its trigger edge (exposure start
  // or end, as the driver stamps it). A pair takes the edge nearest (left timestamp -
  // edge_delay) within edge_tolerance. Not given: learned from the first pairs.
  std::optional<Nanoseconds> edge_delay = std::nullopt;
  Nanoseconds edge_tolerance = 2'000'000;
};

// Pairs left and right frames by time: a left and a right frame pair when their timestamps lie
// within the tolerance, the nearest in time winning; each frame pairs at most once; older frames
// left without a partner are dropped (unpaired); frames on different clocks never pair
// (mismatched). The cameras' own frame numbers are never trusted to pair: a dropped frame or a
// reopened camera makes them differ for good.
//
// With a trigger record (one trigger fires both cameras), each pair then takes the edge at its
// time: the record's edge nearest (left timestamp - edge_delay) within edge_tolerance, and
// carries that edge and its number. A pair with no edge there (an edge the record missed) is
// dropped (off_trigger); an edge the cameras never saw (an extra one) is simply never taken: a
// glitch of the line costs at most its own pair, and every later pair still carries its own
// edge. Without a record, the pair's number is the left camera's sequence.
//
// Edge delay unknown: the first kLearnPairs pairs each take the newest edge at or before
// (left timestamp + period/4), and the median of their delays is the edge delay from then on
// (frames must be stamped less than three quarters of a period after their edge). Fixed memory;
// never allocates.
class StereoPairer {
 public:
  static constexpr std::size_t kLearnPairs = 15;
  static constexpr std::uint32_t kRelearnAfter = 30;

  // `trigger`: the edges of the trigger line (optional; it must outlive the pairer).
  StereoPairer(CameraSource& left, CameraSource& right, PairingConfig config,
               const TriggerRecord* trigger = nullptr);

  // Hands a frame of one side to the pairer (which owns it from now on). Returns true when
  // a pair became ready.
  bool push(Side side, const Frame& frame);
  bool has_pair() const { return ready_; }
  // Takes the ready pair; the caller releases both frames (release()).
  StereoPair take();
  void release(const StereoPair& pair);
  // Drops what waits on one side (its camera was reopened); counted as unpaired.
  void reset(Side side);
  // Counts a damaged frame a camera reported (it never reaches the pairer), with its time.
  void count_corrupt(Side side, const Frame& frame);
  // Tries again a pair that waits for its edge to be recorded (the trigger thread may take it a
  // little after the frames came); StereoGrabber calls it before it waits for more frames.
  void retry();
  // The trigger's rate changed: the tolerances are checked against the new period as the
  // constructor checks them. Throws Error (and keeps the old period) when they do not fit.
  void set_trigger_period(Nanoseconds period);
  std::size_t waiting(Side side) const { return queue(side).size; }
  // The edge delay in use: the configured one, the learned one, or none while it is learned.
  std::optional<Nanoseconds> edge_delay() const { return delay_; }
  const PairingCounters& counters() const { return counters_; }
  const PairingConfig& config() const { return config_; }
  const TriggerRecord* trigger() const { return trigger_; }
  // What became of each trigger: the pairer tells it which frames came and which failed; the
  // caller tells it which of the pairs it took were published and which it skipped.
  TriggerLedger& ledger() { return ledger_; }
  const TriggerLedger& ledger() const { return ledger_; }

 private:
  static constexpr std::size_t kCapacity = 4;
  struct Queue {
    std::array<Frame, kCapacity> frames{};
    std::size_t head = 0, size = 0;
    bool has_last = false;
    std::uint32_t last = 0;
    Nanoseconds last_time = 0;
    const Frame& front() const { return frames[head]; }
    const Frame& second() const { return frames[(head + 1) % kCapacity]; }
  };
  // What the record says of the edge at a frame's time.
  struct EdgeAt {
    enum Kind { found, none, not_yet } kind = none;
    TriggerEdge edge{};
  };
  Queue& queue(Side side) { return side == Side::left ? left_q_ : right_q_; }
  const Queue& queue(Side side) const { return side == Side::left ? left_q_ : right_q_; }
  CameraSource& camera(Side side) { return side == Side::left ? left_ : right_; }
  EdgeAt edge_at(const Frame& frame) const;
  // The trigger number the ledger knows a frame by: its edge's (none found: none); free
  // running, the left camera's sequence (the right camera's count for nothing).
  std::optional<std::uint32_t> trigger_number(Side side, const Frame& frame) const;
  // The ledger hears of every frame that goes, with the number of its edge (free running: the
  // left camera's numbers are the triggers').
  void note_seen(Side side, const Frame& frame);
  void drop_front(Side side, std::uint64_t& counter);
  bool fronts_match_by_time();
  void match();
  void learn(Nanoseconds delay);
  void take_fronts(const std::optional<TriggerEdge>& edge);
  void check_period(Nanoseconds period) const;

  CameraSource& left_;
  CameraSource& right_;
  PairingConfig config_;
  const TriggerRecord* trigger_;
  std::optional<Nanoseconds> delay_;
  std::array<Nanoseconds, kLearnPairs> samples_{};
  std::size_t sample_count_ = 0;
  std::uint32_t edgeless_in_a_row_ = 0;
  bool has_last_edge_ = false;
  std::uint32_t last_edge_ = 0;
  Queue left_q_, right_q_;
  StereoPair pair_{};
  bool ready_ = false;
  PairingCounters counters_{};
  TriggerLedger ledger_;
};

enum class PairStatus { ok, timeout, device_lost };

struct PairResult {
  PairStatus status = PairStatus::timeout;
  StereoPair pair{};
  Side lost_side = Side::left;  // with device_lost
};

// Acquires from two cameras and pairs their frames: next() returns the next pair, or timeout
// when none came before the timeout, or device_lost naming the side that is gone. A corrupt
// frame is counted (left().corrupt/right) and the wait goes on.
class StereoGrabber {
 public:
  StereoGrabber(CameraSource& left, CameraSource& right, Clock& clock, PairingConfig config,
                const TriggerRecord* trigger = nullptr);
  PairResult next(Nanoseconds timeout);
  void release(const StereoPair& pair) { pairer_.release(pair); }
  StereoPairer& pairer() { return pairer_; }
  const StereoPairer& pairer() const { return pairer_; }

 private:
  AcquireStatus acquire(Side side, Nanoseconds timeout);
  CameraSource& left_;
  CameraSource& right_;
  Clock& clock_;
  StereoPairer pairer_;
};

}  // namespace epipole::hal
