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

}  // namespace epipole::test
