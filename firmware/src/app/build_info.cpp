#include "epipole/firmware/build_info.hpp"

#include "epipole/core/error.hpp"
#include "epipole/core/simd.hpp"
#include "version.hpp"

namespace epipole::firmware {

std::string build_info() {
  return cat("epipole ", kVersion, " (", kBuildType, ", ", simd_description(), ", gcc ",
             __VERSION__, ")");
}

}  // namespace epipole::firmware
