#pragma once

// What a kernel compiled without ThreadSanitizer's instrumentation reads and writes, told to it
// by the instrumented code that calls the kernel, a range at a time. ThreadSanitizer checks
// each 16- or 32-byte vector access through its slow range path, which in the host-tsan
// preset cost most of a run (vision/CMakeLists.txt says which kernels are left out). Between
// two synchronisations one range access per buffer is the same to its race detection as the
// kernel's own accesses. Without ThreadSanitizer these do nothing.
#include <cstddef>

#if defined(__SANITIZE_THREAD__)
#define EPIPOLE_TSAN 1
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define EPIPOLE_TSAN 1
#endif
#endif

#ifdef EPIPOLE_TSAN
// ThreadSanitizer's runtime entry points for accesses of any size (what the compiler's own
// instrumentation calls).
extern "C" void __tsan_read_range(void* addr, unsigned long size);   // NOLINT
extern "C" void __tsan_write_range(void* addr, unsigned long size);  // NOLINT
#endif

namespace epipole {

inline void race_check_read([[maybe_unused]] const void* data, [[maybe_unused]] std::size_t bytes) {
#ifdef EPIPOLE_TSAN
  if (bytes > 0) __tsan_read_range(const_cast<void*>(data), bytes);
#endif
}

inline void race_check_write([[maybe_unused]] void* data, [[maybe_unused]] std::size_t bytes) {
#ifdef EPIPOLE_TSAN
  if (bytes > 0) __tsan_write_range(data, bytes);
#endif
}

}  // namespace epipole
