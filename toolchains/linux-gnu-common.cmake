# Shared part of the cross toolchain files; EPIPOLE_CROSS_TRIPLE, EPIPOLE_DEBIAN_ARCH,
# EPIPOLE_QEMU and EPIPOLE_ARCH_FLAGS are set by the including file.
set(CMAKE_C_COMPILER ${EPIPOLE_CROSS_TRIPLE}-gcc)
set(CMAKE_CXX_COMPILER ${EPIPOLE_CROSS_TRIPLE}-g++)
set(CMAKE_C_FLAGS_INIT "${EPIPOLE_ARCH_FLAGS}")
set(CMAKE_CXX_FLAGS_INIT "${EPIPOLE_ARCH_FLAGS}")

# Without a board sysroot, Debian's cross libc lives in /usr/<triple>.
if(CMAKE_SYSROOT)
  set(EPIPOLE_TARGET_ROOT ${CMAKE_SYSROOT})
else()
  set(EPIPOLE_TARGET_ROOT /usr/${EPIPOLE_CROSS_TRIPLE})
endif()
set(CMAKE_FIND_ROOT_PATH ${EPIPOLE_TARGET_ROOT})

# Board-side libraries (yaml-cpp, libgpiod, libcamera) unpacked from Debian's packages of the
# target architecture by scripts/fetch-target-libs.sh; the project links yaml-cpp's and libgpiod's
# static archives and libcamera's shared library, whose own libraries the linker and, under
# qemu, the test programs find there too.
if(DEFINED ENV{EPIPOLE_TARGET_LIBS_DIR})
  set(_target_libs_parent $ENV{EPIPOLE_TARGET_LIBS_DIR})
elseif(DEFINED ENV{XDG_CACHE_HOME})
  set(_target_libs_parent $ENV{XDG_CACHE_HOME}/epipole)
else()
  set(_target_libs_parent $ENV{HOME}/.cache/epipole)
endif()
set(EPIPOLE_TARGET_LIBS ${_target_libs_parent}/target-libs-${EPIPOLE_DEBIAN_ARCH}
    CACHE PATH "Target libraries unpacked by scripts/fetch-target-libs.sh")
set(_target_lib_dirs ${EPIPOLE_TARGET_LIBS}/usr/lib/${EPIPOLE_CROSS_TRIPLE}
                     ${EPIPOLE_TARGET_LIBS}/lib/${EPIPOLE_CROSS_TRIPLE})
if(IS_DIRECTORY ${EPIPOLE_TARGET_LIBS})
  list(APPEND CMAKE_FIND_ROOT_PATH ${EPIPOLE_TARGET_LIBS})
endif()
# Always, so that a build configured before the libraries were fetched links once they are.
# The architecture's own headers (jconfig.h, OpenCV's cvconfig.h) are where a multiarch
# compiler looks for them, which the cross compiler does not know of.
string(APPEND CMAKE_C_FLAGS_INIT " -isystem ${EPIPOLE_TARGET_LIBS}/usr/include/${EPIPOLE_CROSS_TRIPLE}")
string(APPEND CMAKE_CXX_FLAGS_INIT " -isystem ${EPIPOLE_TARGET_LIBS}/usr/include/${EPIPOLE_CROSS_TRIPLE}")
foreach(_dir ${_target_lib_dirs})
  string(APPEND CMAKE_EXE_LINKER_FLAGS_INIT " -Wl,-rpath-link,${_dir}")
  string(APPEND CMAKE_SHARED_LINKER_FLAGS_INIT " -Wl,-rpath-link,${_dir}")
endforeach()
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)

# ctest runs the cross-built test programs under qemu-user with the target's libraries.
find_program(EPIPOLE_QEMU_PATH ${EPIPOLE_QEMU})
if(EPIPOLE_QEMU_PATH)
  list(JOIN _target_lib_dirs ":" _target_library_path)
  set(CMAKE_CROSSCOMPILING_EMULATOR ${EPIPOLE_QEMU_PATH} -L ${EPIPOLE_TARGET_ROOT} -E
                                    LD_LIBRARY_PATH=${_target_library_path})
endif()
