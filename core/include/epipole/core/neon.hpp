#pragma once

// The one place that knows whether NEON is native. Kernels written with NEON intrinsics include
// this header; on ARM it is <arm_neon.h>, elsewhere SIMDe implements the same intrinsics with
// the host's vector unit, so host tests run the code that ships.
#if defined(__ARM_NEON) || defined(__ARM_NEON__)
#include <arm_neon.h>
#else
#ifndef SIMDE_ENABLE_NATIVE_ALIASES
#define SIMDE_ENABLE_NATIVE_ALIASES
#endif
#include <simde/arm/neon.h>
#endif
