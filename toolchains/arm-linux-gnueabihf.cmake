# Cross build for 32-bit ARMv7 boards with NEON (hard float) with Debian's
# g++-arm-linux-gnueabihf. Tests run under qemu-arm (Debian's qemu-user).
#
#   -DEPIPOLE_CPU=cortex-a7|cortex-a53|cortex-a72|...   the board's core (-mcpu)
#   -DCMAKE_SYSROOT=/path/to/board-sysroot              optional: the board's libraries
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR armv7l)
set(EPIPOLE_CROSS_TRIPLE arm-linux-gnueabihf)
set(EPIPOLE_DEBIAN_ARCH armhf)
set(EPIPOLE_QEMU qemu-arm)

set(EPIPOLE_CPU "cortex-a7" CACHE STRING "Target core for -mcpu")
set_property(CACHE EPIPOLE_CPU PROPERTY STRINGS cortex-a72 cortex-a53 cortex-a15 cortex-a9 cortex-a7)
# -Wno-psabi: GCC notes, for every std::vector of a small struct, that its parameter passing
# changed in GCC 7.1; that matters only when linking objects built by an older GCC (none here).
set(EPIPOLE_ARCH_FLAGS "-mcpu=${EPIPOLE_CPU} -mfpu=neon-vfpv4 -mfloat-abi=hard -Wno-psabi")

include(${CMAKE_CURRENT_LIST_DIR}/linux-gnu-common.cmake)
