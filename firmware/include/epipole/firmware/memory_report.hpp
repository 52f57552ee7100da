#pragma once

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

namespace epipole::firmware {

// The memory a board's frame loop holds, part by part: the buffers each part allocated at
// start-up (what `epipole-fw --check` prints, and what the board's memory_budget_mb bounds).
// A test holds the total to the heap the firmware really keeps after its construction.
class MemoryReport {
 public:
  struct Part {
    std::string name;
    std::size_t bytes = 0;
  };
  void add(std::string name, std::size_t bytes) { parts_.push_back({std::move(name), bytes}); }
  const std::vector<Part>& parts() const { return parts_; }
  std::vector<Part>& parts() { return parts_; }
  std::size_t total() const {
    std::size_t sum = 0;
    for (const Part& p : parts_) sum += p.bytes;
    return sum;
  }

 private:
  std::vector<Part> parts_;
};

}  // namespace epipole::firmware
