#pragma once

#include <cstddef>

namespace epipole::test {

// Counts calls of the global operator new (every form) made by this thread while an
// AllocationCounter is alive. The test program that links allocation_counter.cpp replaces
// operator new/delete; the counter is how the fixed-memory rule is checked.
class AllocationCounter {
 public:
  AllocationCounter();
  ~AllocationCounter();
  AllocationCounter(const AllocationCounter&) = delete;
  AllocationCounter& operator=(const AllocationCounter&) = delete;
  std::size_t count() const;
};

// Every operator new call of the whole program so far, in any thread (for code that runs on
// threads of its own: compare two readings taken while nothing else runs).
std::size_t allocations_in_all_threads();
// The bytes operator new has handed out and not yet had back (usable sizes of the blocks).
std::size_t live_bytes_in_all_threads();

}  // namespace epipole::test
