#pragma once

#include <string>
#include <string_view>

namespace epipole {

// Which implementation of a vision kernel runs. `reference` is the scalar code that defines
// every result; `neon` is the NEON code (native on ARM, through SIMDe on other hosts).
enum class SimdPath { reference, neon };

// True when this CPU can run the NEON kernels: always on aarch64 and on hosts that build them
// through SIMDe; on 32-bit ARM it is read from the kernel's hardware capabilities (HWCAP).
bool cpu_has_neon();

// The fastest path this CPU supports, decided once.
SimdPath best_simd_path();

// "auto" (best_simd_path()), "ref" or "reference", "neon"; throws Error naming the value
// otherwise, and when NEON is asked for on a CPU without it.
SimdPath parse_simd_path(std::string_view name);

std::string_view to_string(SimdPath path);

// A line for logs and --version: e.g. "neon (native, aarch64)" or "neon (SIMDe on x86_64)".
std::string simd_description();

}  // namespace epipole
