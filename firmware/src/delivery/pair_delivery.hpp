#pragma once

#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "delivery/pair_copy.hpp"
#include "epipole/firmware/health_report.hpp"
#include "epipole/firmware/journal.hpp"

namespace epipole::firmware::outputs {

// What an output did with the pairs it was offered.
struct DeliveryCounters {
  std::uint64_t delivered = 0;  // handed to the output's work and done
  std::uint64_t dropped = 0;    // overwritten while waiting: the output's work was behind
  std::uint64_t failures = 0;   // the work threw (a full disk, a network error): counted, gone on
  std::uint64_t work_ns = 0;    // the work's time on the delivered pairs, summed (steady clock)
};

// How the frame loop hands pairs to one output without waiting for it: a few copies of the
// output's parts (PairCopy), allocated by the constructor, and a thread of the output's own that
// does its work on them, one at a time, oldest first. A pair offered while every copy is taken
// replaces the oldest one still waiting (the output gets the freshest pairs; the one replaced is
// counted dropped), so offer() only ever copies. The latest health message waits beside the
// pairs, for outputs that send it too (a newer one replaces it); the work takes pairs and health
// in the order they were offered.
//
// The work runs on the thread started by start() and stopped by stop() (or the destructor): an
// exception from it is counted in failures, said in the journal (a line a minute at most) and
// the thread goes on with the next pair. Declare a PairDelivery after everything its work uses,
// so that its thread is stopped before they go.
class PairDelivery {
 public:
  using Work = std::function<void(const PairCopy&)>;
  using HealthWork = std::function<void(const HealthReport&)>;

  // `name` names the output in the journal; `copies` >= 2 (one in work, one waiting).
  PairDelivery(std::string name, const BoardConfig& board, PairParts parts, Work work,
               HealthWork health_work = nullptr, int copies = 2);
  ~PairDelivery();
  PairDelivery(const PairDelivery&) = delete;
  PairDelivery& operator=(const PairDelivery&) = delete;

  void start();
  // Finishes the pair in work and those waiting (at most copies - 1), then returns.
  void stop();

  // Frame loop side: never waits for the work, never allocates.
  void offer(const FrameResult& result, const PairStamp& stamp);
  void offer_health(const HealthReport& report);

  DeliveryCounters counters() const;
  std::size_t working_set_bytes() const;
  const std::string& name() const { return name_; }

 private:
  enum class Slot { free, filling, waiting, working };
  void run();
  std::size_t oldest_waiting() const;  // slots_.size(): none
  template <class DoWork>
  void do_work(DoWork&& work);

  std::string name_;
  Work work_;
  HealthWork health_work_;
  std::vector<PairCopy> copies_;
  std::vector<Slot> slots_;
  std::vector<std::uint64_t> order_;  // when each waiting copy was offered
  std::uint64_t offered_ = 0;
  std::optional<HealthReport> health_;
  std::uint64_t health_order_ = 0;  // when it was offered, among the pairs
  HealthReport health_in_work_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;
  DeliveryCounters counters_;
  JournalLimit faults_said_{60'000'000'000};
  std::thread thread_;
};

}  // namespace epipole::firmware::outputs
