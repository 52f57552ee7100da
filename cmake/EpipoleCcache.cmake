# Compiles through ccache when it is installed (Debian: ccache), so a rebuild in another clone
# or build folder - CI's fresh clone of every run - compiles only what changed.
# The cache is ccache's own (~/.cache/ccache unless CCACHE_DIR says otherwise).
#
# What makes a fresh clone hit the cache:
# - base_dir: absolute paths inside the source tree (sources, -I, the precompiled headers'
#   -include) become relative, so the clone's folder does not enter the hash;
# - hash_dir off: -g puts the working folder into the objects; ignoring it means an object's
#   debug info may name the folder of the build that first compiled it;
# - sloppiness pch_defines,time_macros: needed for ccache to cache a file that uses a
#   precompiled header; include_file_mtime/ctime: a fresh checkout's headers are all new;
# - pch_external_checksum: a precompiled header (over 100 MB) is known by the checksum that
#   cmake/ccache-launcher.sh writes beside it when it is made, not hashed again on every compile
#   that uses it. The namespace keeps these entries apart from those made before the checksum
#   files: those name the header itself, still match, and would go on hashing it on every hit.
# - depend_mode: on a miss ccache runs the compiler only, and takes the headers a file read from
#   the dependency file the compiler writes anyway (-MD, as Ninja asks), rather than running the
#   preprocessor first to hash its output. On a new machine every file misses: two of the host
#   preset's files, each compiled three times, took 45.4 s of CPU with that pass, 40.0 s in depend
#   mode and 40.9 s without ccache.
# Paths compiled into test programs (the tool, the data) live in one generated file
# (tests/CMakeLists.txt), not in the flags of every file.
option(EPIPOLE_CCACHE "Compile through ccache when it is found" ON)
if(NOT EPIPOLE_CCACHE OR CMAKE_C_COMPILER_LAUNCHER OR CMAKE_CXX_COMPILER_LAUNCHER)
  return()
endif()
find_program(EPIPOLE_CCACHE_PROGRAM ccache)
if(NOT EPIPOLE_CCACHE_PROGRAM)
  return()
endif()
set(_launcher
    ${CMAKE_COMMAND} -E env
    CCACHE_BASEDIR=${PROJECT_SOURCE_DIR}
    CCACHE_NOHASHDIR=1
    CCACHE_SLOPPINESS=pch_defines,time_macros,include_file_mtime,include_file_ctime
    CCACHE_PCH_EXTSUM=true
    CCACHE_NAMESPACE=pch-checksum
    CCACHE_DEPEND=true
    ${CMAKE_CURRENT_LIST_DIR}/ccache-launcher.sh ${EPIPOLE_CCACHE_PROGRAM})
set(CMAKE_C_COMPILER_LAUNCHER ${_launcher})
set(CMAKE_CXX_COMPILER_LAUNCHER ${_launcher})
message(STATUS "Compiling through ccache (${EPIPOLE_CCACHE_PROGRAM})")
