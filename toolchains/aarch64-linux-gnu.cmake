# Cross build for 64-bit ARM boards (Raspberry Pi 5, RK3588, Jetson) with Debian's
# g++-aarch64-linux-gnu. Tests run under qemu-aarch64 (Debian's qemu-user).
#
#   -DEPIPOLE_CPU=cortex-a76|cortex-a72|cortex-a53|...   the board's core (-mcpu)
#   -DCMAKE_SYSROOT=/path/to/board-sysroot               optional: the board's libraries
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(EPIPOLE_CROSS_TRIPLE aarch64-linux-gnu)
set(EPIPOLE_DEBIAN_ARCH arm64)
set(EPIPOLE_QEMU qemu-aarch64)

set(EPIPOLE_CPU "cortex-a72" CACHE STRING "Target core for -mcpu")
set_property(CACHE EPIPOLE_CPU PROPERTY STRINGS cortex-a76 cortex-a72 cortex-a55 cortex-a53)
set(EPIPOLE_ARCH_FLAGS "-mcpu=${EPIPOLE_CPU}")

include(${CMAKE_CURRENT_LIST_DIR}/linux-gnu-common.cmake)
