# NEON everywhere: on ARM the kernels include <arm_neon.h>; on other hosts the same source is
# compiled through SIMDe, so host tests exercise the code that ships.
add_library(epipole_neon INTERFACE)

if(CMAKE_SYSTEM_PROCESSOR MATCHES "^(aarch64|arm64|arm.*)$")
  set(EPIPOLE_NEON_NATIVE ON)
else()
  set(EPIPOLE_NEON_NATIVE OFF)
  find_path(SIMDE_INCLUDE_DIR simde/arm/neon.h REQUIRED
            DOC "SIMDe headers (Debian: libsimde-dev)")
  target_include_directories(epipole_neon SYSTEM INTERFACE ${SIMDE_INCLUDE_DIR})
endif()

# x86 hosts: a baseline every laptop of the last decade has (SSE4.2, POPCNT); SIMDe maps NEON
# onto it. Set EPIPOLE_X86_MARCH to "native" for the fastest host build, or empty to leave
# the compiler default.
if(CMAKE_SYSTEM_PROCESSOR MATCHES "^(x86_64|AMD64|amd64)$")
  set(EPIPOLE_X86_MARCH "x86-64-v2" CACHE STRING "-march for x86 hosts (empty: compiler default)")
  if(EPIPOLE_X86_MARCH)
    add_compile_options(-march=${EPIPOLE_X86_MARCH})
  endif()
endif()
