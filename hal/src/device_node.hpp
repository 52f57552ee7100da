#pragma once

// Opening a device node (a camera, a serial port) the way every backend reports it.
#include <fcntl.h>

#include <cerrno>
#include <cstring>
#include <string>

#include "epipole/core/error.hpp"
#include "epipole/hal/device_missing.hpp"

namespace epipole::hal::detail {

// open(2) of `path`; a node that is not there (ENOENT, ENODEV, ENXIO: not plugged in yet, or
// gone) throws DeviceMissing, any other failure Error, both as "<what> <path>: ...".
inline int open_device_node(const std::string& path, int flags, const char* what) {
  const int fd = ::open(path.c_str(), flags);
  if (fd >= 0) return fd;
  const int error = errno;
  if (error == ENOENT || error == ENODEV || error == ENXIO) {
    throw DeviceMissing(cat(what, " ", path, ": not there (yet): ", std::strerror(error)));
  }
  throw Error(cat(what, " ", path, ": cannot open: ", std::strerror(error)));
}

}  // namespace epipole::hal::detail
