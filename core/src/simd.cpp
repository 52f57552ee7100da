#include "epipole/core/simd.hpp"

#include "epipole/core/error.hpp"

#if defined(__arm__)
#include <asm/hwcap.h>
#include <sys/auxv.h>
#endif

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

bool neon_is_native() {
#if defined(__ARM_NEON) || defined(__ARM_NEON__)
  return true;
#else
  return false;
#endif
}

}  // namespace

bool cpu_has_neon() {
#if defined(__arm__)
  static const bool has = (getauxval(AT_HWCAP) & HWCAP_NEON) != 0;
  return has;
#else
  return true;
#endif
}

SimdPath best_simd_path() {
  return cpu_has_neon() ? SimdPath::neon : SimdPath::reference;
}

SimdPath parse_simd_path(std::string_view name) {
  if (name == "auto") return best_simd_path();
  if (name == "ref" || name == "reference") return SimdPath::reference;
  if (name == "neon") {
    require(cpu_has_neon(), "kernel path 'neon' asked for, but this CPU has no NEON");
    return SimdPath::neon;
  }
  throw Error(cat("unknown kernel path '", name, "' (expected auto, ref or neon)"));
}

std::string_view to_string(SimdPath path) {
  switch (path) {
    case SimdPath::reference:
      return "ref";
    case SimdPath::neon:
      return "neon";
  }
  return "?";
}

std::string simd_description() {
  if (!cpu_has_neon()) return cat("ref (no NEON on this ", kArchitecture, " CPU)");
  return neon_is_native() ? cat("neon (native, ", kArchitecture, ")")
                          : cat("neon (SIMDe on ", kArchitecture, ")");
}

}  // namespace epipole
