#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "epipole/hal/camera.hpp"
#include "epipole/hal/clock.hpp"
#include "epipole/hal/side.hpp"
#include "epipole/hal/trigger.hpp"
#include "epipole/hal/trigger_ledger.hpp"

namespace epipole::hal {

struct StereoPair {
  Frame left;
  Frame right;
};

// Everything the pairer did with the frames of one side.
// pushed = paired + unpaired + mismatched + out_of_order + off_trigger + (frames still waiting).
struct PairingSideCounters {
  std::uint64_t pushed = 0;
  // The other side never had that trigger (by time: no frame of the other side was nearest
  // within the tolerance).
  std::uint64_t unpaired = 0;
  // Same sequence, |dt| > tolerance; or the two frames are on different clocks.
  std::uint64_t mismatched = 0;
  // The sequence (by time: or the timestamp) did not increase on its side.
  std::uint64_t out_of_order = 0;
  // Same sequence and |dt| within the tolerance, but the trigger record has no edge of that
  // sequence at the frames' time (both cameras garbled the sequence the same way).
  std::uint64_t off_trigger = 0;
  // Damaged frames the cameras reported (AcquireStatus::corrupt); never pushed (StereoGrabber).
  std::uint64_t corrupt = 0;
  // Pairing by sequence: the times a reopened side's frames were given trigger numbers again.
  std::uint64_t renumbered = 0;
};

struct PairingCounters {
  std::uint64_t pairs = 0;
  std::array<PairingSideCounters, 2> sides{};  // by Side
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
  // can never pass a timestamp check. 0: not checked.
  Nanoseconds trigger_period = 0;
  // With a trigger record: a pair of sequence s is accepted only when the record holds edge s
  // and both frame timestamps lie within edge_tolerance of (edge s + edge_delay). edge_delay is
  // the board's frame timestamp minus its trigger edge (exposure start or end, as the driver
  // stamps it).
  Nanoseconds edge_delay = 0;
  Nanoseconds edge_tolerance = 2'000'000;
  // true: frames pair by trigger sequence (one trigger fires both cameras). false: by time
  // alone, for free-running cameras that count their frames each on its own: a left and a
  // right frame pair when their timestamps lie within the tolerance, the nearest in time
  // winning; each frame pairs at most once; older frames left without a partner are dropped
  // (unpaired); frames on different clocks never pair (mismatched). The pair's number is the
  // left frame's sequence. No trigger record is used.
  bool match_sequences = true;
};

// Pairs left and right frames by trigger sequence (or by time alone: match_sequences). A left and a
// right frame become a pair only when their sequences are equal AND their timestamps lie within the
// tolerance AND, when a trigger record is given, the trigger's own edge of that sequence lies where
// their timestamps say; a frame whose sequence does not increase on its side is refused; a frame
// for which the other side has moved past its sequence is dropped. Dropped frames go back to their
// camera at once and are counted. Fixed memory; never allocates.
//
// A reopened camera (reset()) counts its frames again from wherever its driver starts (V4L2: 0 at
// every stream start), so its numbers say nothing about the trigger any more. Its frames wait
// until one matches, by time within the tolerance, a frame of the other side (or, both sides
// reopened and a trigger record given, an edge of the record): the difference of the two
// numbers is then added to each of its frames, and they pair by sequence again. With both sides
// reopened and no record, the first match numbers on after the newest frame the ledger counted.
class StereoPairer {
 public:
  // `trigger`: the edges of the trigger line (optional; it must outlive the pairer). Without it,
  // a sequence garbled identically on both cameras still pairs (the frames are of one trigger,
  // as the timestamps prove, but carry the wrong number).
  StereoPairer(CameraSource& left, CameraSource& right, PairingConfig config,
               const TriggerRecord* trigger = nullptr);

  // Hands a frame of one side to the pairer (which owns it from now on). Returns true when
  // a pair became ready.
  bool push(Side side, const Frame& frame);
  bool has_pair() const { return ready_; }
  // Takes the ready pair; the caller releases both frames (release()).
  StereoPair take();
  void release(const StereoPair& pair);
  // Drops what waits on one side (its camera was reopened); counted as unpaired. Pairing by
  // sequence, that side's frames are numbered anew from their next match.
  void reset(Side side);
  // Counts a damaged frame a camera reported (it never reaches the pairer); `camera_sequence`
  // is the number the camera gave it, for the trigger ledger.
  void count_corrupt(Side side, std::uint32_t camera_sequence);
  // The trigger's rate changed: the tolerances are checked against the new period as the
  // constructor checks them. Throws Error (and keeps the old period) when they do not fit.
  void set_trigger_period(Nanoseconds period);
  std::size_t waiting(Side side) const { return queue(side).size; }
  // Whether a pair's number is still its trigger's: false from the time both sides were numbered
  // anew without a trigger record (their numbers go on after the newest frame before), until both
  // are numbered by the record again. Pairing by time: the left camera's numbers, as they come.
  bool numbers_are_the_triggers() const { return numbers_are_the_triggers_; }
  const PairingCounters& counters() const { return counters_; }
  const PairingConfig& config() const { return config_; }
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
    bool numbered = true;      // false after reset(), until the side's next match
    std::uint32_t offset = 0;  // added to the camera's sequence: the trigger's number
    const Frame& front() const { return frames[head]; }
    const Frame& second() const { return frames[(head + 1) % kCapacity]; }
  };
  Queue& queue(Side side) { return side == Side::left ? left_q_ : right_q_; }
  const Queue& queue(Side side) const { return side == Side::left ? left_q_ : right_q_; }
  CameraSource& camera(Side side) { return side == Side::left ? left_ : right_; }
  void drop_front(Side side, std::uint64_t& counter);
  // The ledger hears of a side's frames once they carry the trigger's number (pairing by time,
  // the left camera's numbers are the triggers').
  void note_seen(Side side, std::uint32_t number);
  bool on_trigger(const Frame& left, const Frame& right) const;
  void match();
  bool fronts_match_by_time();
  void match_by_time();
  bool renumber();
  void number(Side side, std::uint32_t offset);
  void take_fronts();
  void check_period(Nanoseconds period) const;

  CameraSource& left_;
  CameraSource& right_;
  PairingConfig config_;
  const TriggerRecord* trigger_;
  Queue left_q_, right_q_;
  StereoPair pair_{};
  bool ready_ = false;
  bool numbers_are_the_triggers_ = true;
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
