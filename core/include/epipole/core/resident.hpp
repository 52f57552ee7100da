// Fixed memory that is resident from start-up. A buffer reserved but not yet written is only
// address space: its pages are faulted in when a pair first writes them, minutes into a run (a
// latency spike in the frame loop, and resident memory that seems to grow). Writing every byte
// once when the buffer is made takes those faults at start-up.
#pragma once

#include <cstddef>
#include <vector>

namespace epipole {

// v.reserve(n), with the reserved memory written once; v is left empty.
template <typename T>
void reserve_resident(std::vector<T>& v, std::size_t n) {
  v.reserve(n);
  v.resize(v.capacity());
  v.clear();
}

}  // namespace epipole
