# One interface target carries the project's warning policy; every Epipole target links it.
#
# -Wconversion is on because silent narrowing in pixel arithmetic is the classic source of
# off-by-one-grey-level bugs; -Wsign-conversion stays off because indexing with size_t vs int
# would bury the useful warnings under casts. -Wold-style-cast keeps every conversion visible.
add_library(epipole_warnings INTERFACE)
target_compile_options(epipole_warnings INTERFACE
  -Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wno-sign-conversion
  -Wnon-virtual-dtor -Wold-style-cast -Woverloaded-virtual -Wcast-align
  -Wdouble-promotion -Wformat=2 -Wimplicit-fallthrough -Wmisleading-indentation -Wundef)
if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
  target_compile_options(epipole_warnings INTERFACE -Wduplicated-cond -Wlogical-op)
endif()
if(EPIPOLE_WERROR)
  target_compile_options(epipole_warnings INTERFACE -Werror)
endif()
