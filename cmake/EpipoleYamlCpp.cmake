# yaml-cpp as the imported target epipole::yaml-cpp. Host builds take Debian's shared library;
# cross builds take the static archive unpacked by scripts/fetch-target-libs.sh, so the ARM test
# programs run under qemu without extra library paths.
if(CMAKE_CROSSCOMPILING)
  set(_yaml_names libyaml-cpp.a yaml-cpp)
else()
  set(_yaml_names yaml-cpp)
endif()
find_path(EPIPOLE_YAML_CPP_INCLUDE_DIR yaml-cpp/yaml.h)
find_library(EPIPOLE_YAML_CPP_LIBRARY NAMES ${_yaml_names})
if(EPIPOLE_YAML_CPP_INCLUDE_DIR AND EPIPOLE_YAML_CPP_LIBRARY)
  add_library(epipole::yaml-cpp UNKNOWN IMPORTED GLOBAL)
  set_target_properties(epipole::yaml-cpp PROPERTIES
    IMPORTED_LOCATION ${EPIPOLE_YAML_CPP_LIBRARY}
    INTERFACE_INCLUDE_DIRECTORIES ${EPIPOLE_YAML_CPP_INCLUDE_DIR})
  set(EPIPOLE_HAVE_YAML_CPP ON)
else()
  set(EPIPOLE_HAVE_YAML_CPP OFF)
  if(CMAKE_CROSSCOMPILING)
    message(FATAL_ERROR "yaml-cpp for the target was not found: run scripts/fetch-target-libs.sh "
                        "${EPIPOLE_DEBIAN_ARCH} (or give -DCMAKE_SYSROOT=...)")
  else()
    message(FATAL_ERROR "yaml-cpp not found: run scripts/setup.sh (Debian: libyaml-cpp-dev)")
  endif()
endif()
