#pragma once

// Reads and writes on a non-blocking file descriptor with poll timeouts: the I/O of every
// serial-port backend (termios devices, pseudo-terminal masters).
#include <cstddef>
#include <span>

#include "epipole/hal/serial_port.hpp"

namespace epipole::hal::detail {

// Returns as soon as some bytes are there; hung_up on end of file, EIO or POLLHUP.
IoResult read_fd(int fd, std::span<std::byte> buffer, Nanoseconds timeout);
// Writes all bytes, or reports how many went before the timeout or the hang-up.
IoResult write_fd(int fd, std::span<const std::byte> data, Nanoseconds timeout);

}  // namespace epipole::hal::detail
