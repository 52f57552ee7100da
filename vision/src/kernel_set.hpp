#pragma once

// How a stage picks its kernel for a SimdPath. Native x86 kernels are compiled only on x86
// hosts (EPIPOLE_HAVE_AVX2_KERNELS, set by vision/CMakeLists.txt); this header is the one place
// that knows, so stages never test the ISA themselves.
#include "epipole/core/simd.hpp"

#if EPIPOLE_HAVE_AVX2_KERNELS
#define EPIPOLE_AVX2_KERNEL(function) (function)
#else
#define EPIPOLE_AVX2_KERNEL(function) nullptr
#endif

namespace epipole::vision {

template <typename Function>
struct KernelSet {
  Function* reference;
  Function* neon;
  Function* avx2;  // null where the stage or the build has none: the NEON kernel runs instead

  Function* pick(SimdPath path) const {
    switch (path) {
      case SimdPath::reference:
        return reference;
      case SimdPath::neon:
        return neon;
      case SimdPath::avx2:
        return avx2 != nullptr ? avx2 : neon;
    }
    return reference;
  }
};

}  // namespace epipole::vision
