#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace epipole {

// Which implementation of a vision kernel runs.
//   reference  the scalar code that defines every result;
//   neon       the NEON code (native on ARM, through SIMDe on other hosts): the code that ships;
//   avx2       native x86 code for hosts with AVX2, where host speed matters. A stage without an
//              AVX2 kernel runs its NEON one on this path.
enum class SimdPath { reference, neon, avx2 };

// True when this CPU can run the NEON kernels: always on aarch64 and on hosts that build them
// through SIMDe; on 32-bit ARM it is read from the kernel's hardware capabilities (HWCAP).
bool cpu_has_neon();

// True on x86 CPUs with AVX2 (always false on ARM builds).
bool cpu_has_avx2();

bool simd_path_available(SimdPath path);

// Every path this CPU can run, the reference first.
std::vector<SimdPath> available_simd_paths();

// The fastest path this CPU supports (avx2, else neon, else reference), decided once.
SimdPath best_simd_path();

// "auto" (best_simd_path()), "ref" or "reference", "neon", "avx2"; throws Error naming the
// value when it is unknown or when this CPU cannot run it.
SimdPath parse_simd_path(std::string_view name);

std::string_view to_string(SimdPath path);

// A line for logs and --version: e.g. "neon (native, aarch64)" or "avx2 (x86_64; neon through
// SIMDe also available)".
std::string simd_description();

}  // namespace epipole
