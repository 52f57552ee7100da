#pragma once

#include <cstddef>
#include <span>
#include <string>

#include "epipole/hal/clock.hpp"

namespace epipole::hal {

enum class IoStatus {
  ok,       // bytes moved (read: at least one)
  timeout,  // nothing could be moved before the timeout
  hung_up,  // the other end is gone (cable, USB adapter, pty master closed): reopen
  closed,   // the port is not open
};

struct IoResult {
  IoStatus status = IoStatus::closed;
  std::size_t bytes = 0;
};

// A byte link to the robot's controller: 8N1, raw, non-blocking underneath, with timeouts.
// read() returns as soon as some bytes are there; write() moves all bytes or reports how many
// went before the timeout or the hang-up. Neither throws once the port is open.
class SerialPort {
 public:
  virtual ~SerialPort() = default;
  virtual IoResult read(std::span<std::byte> buffer, Nanoseconds timeout) = 0;
  virtual IoResult write(std::span<const std::byte> data, Nanoseconds timeout) = 0;
  virtual bool is_open() const = 0;
  // Closes and opens the device again (after a hang-up). Throws Error naming the device when
  // it cannot be opened; the port is then closed and reopen() may be tried again later.
  virtual void reopen() = 0;
  virtual void close() = 0;
  // Where the robot's end of a simulated link is (a pseudo-terminal); empty for a real port.
  virtual std::string peer_path() const { return {}; }
};

struct SerialConfig {
  std::string device;  // e.g. /dev/ttyAMA0, /dev/ttyUSB0, /dev/serial0
  int baud = 115200;
};

// Baud rates a termios port accepts: 9600 .. 4000000 (the standard Linux rates).
bool is_supported_baud(int baud);

}  // namespace epipole::hal
