#include "epipole/core/simd.hpp"

#include "epipole/core/error.hpp"

#if defined(__arm__)
#include <asm/hwcap.h>
#include <sys/auxv.h>
#endif

// This file is the one place that asks the compiler and the CPU what they can do.

namespace epipole {

namespace {

constexpr std::string_view kArchitecture =
#if defined(__aarch64__)
    "aarch64";
#elif defined(__arm__)
    "armv7";
#elif defined(__x86_64__)
    "x86_64";
#else
    "unknown";
#endif

constexpr bool kNeonIsNative =
#if defined(__ARM_NEON) || defined(__ARM_NEON__)
    true;
#else
    false;
#endif

}  // namespace

bool cpu_has_neon() {
#if defined(__arm__)
  static const bool has = (getauxval(AT_HWCAP) & HWCAP_NEON) != 0;
  return has;
#else
  return true;
#endif
}

bool cpu_has_avx2() {
#if defined(__x86_64__)
  static const bool has = __builtin_cpu_supports("avx2") != 0;
  return has;
#else
  return false;
#endif
}

bool simd_path_available(SimdPath path) {
  switch (path) {
    case SimdPath::reference:
      return true;
    case SimdPath::neon:
      return cpu_has_neon();
    case SimdPath::avx2:
      return cpu_has_avx2();
  }
  return false;
}

std::vector<SimdPath> available_simd_paths() {
  std::vector<SimdPath> paths;
  for (const SimdPath path : {SimdPath::reference, SimdPath::neon, SimdPath::avx2}) {
    if (simd_path_available(path)) paths.push_back(path);
  }
  return paths;
}

SimdPath best_simd_path() {
  if (cpu_has_avx2()) return SimdPath::avx2;
  return cpu_has_neon() ? SimdPath::neon : SimdPath::reference;
}

SimdPath parse_simd_path(std::string_view name) {
  if (name == "auto") return best_simd_path();
  SimdPath path;
  if (name == "ref" || name == "reference") {
    path = SimdPath::reference;
  } else if (name == "neon") {
    path = SimdPath::neon;
  } else if (name == "avx2") {
    path = SimdPath::avx2;
  } else {
    throw Error(cat("unknown kernel path '", name, "' (expected auto, ref, neon or avx2)"));
  }
  require(simd_path_available(path), "kernel path '", name, "' asked for, but this ", kArchitecture,
          " CPU cannot run it");
  return path;
}

std::string_view to_string(SimdPath path) {
  switch (path) {
    case SimdPath::reference:
      return "ref";
    case SimdPath::neon:
      return "neon";
    case SimdPath::avx2:
      return "avx2";
  }
  return "?";
}

std::string simd_description() {
  if (cpu_has_avx2()) return cat("avx2 (", kArchitecture, "; neon through SIMDe also available)");
  if (!cpu_has_neon()) return cat("ref (no NEON on this ", kArchitecture, " CPU)");
  return kNeonIsNative ? cat("neon (native, ", kArchitecture, ")")
                       : cat("neon (SIMDe on ", kArchitecture, ")");
}

}  // namespace epipole
