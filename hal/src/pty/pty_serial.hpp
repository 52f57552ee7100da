#pragma once

#include <string>

#include "epipole/hal/serial_port.hpp"
#include "epipole/hal/unique_fd.hpp"

namespace epipole::hal {

// The simulated board's serial link: a kernel pseudo-terminal. The firmware holds the master
// end; the other end (peer_path(), e.g. /dev/pts/3) is where the robot's side connects, as to
// a UART: `epipole link /dev/pts/3`. The peer is kept open and raw by the port itself, so bytes
// written before anyone connects wait in the kernel (up to its buffer) and a robot side may
// come and go without hanging the link up. With a device in the configuration, a symbolic link
// of that name points at the peer (an existing symbolic link is replaced; any other file is
// an error), so tools can use a fixed path.
class PtySerialPort final : public SerialPort {
 public:
  explicit PtySerialPort(SerialConfig config);
  ~PtySerialPort() override;
  PtySerialPort(const PtySerialPort&) = delete;
  PtySerialPort& operator=(const PtySerialPort&) = delete;

  IoResult read(std::span<std::byte> buffer, Nanoseconds timeout) override;
  IoResult write(std::span<const std::byte> data, Nanoseconds timeout) override;
  bool is_open() const override { return static_cast<bool>(master_); }
  // A new pseudo-terminal (and peer path; the symbolic link follows it).
  void reopen() override;
  void close() override;

  std::string peer_path() const override { return peer_path_; }

 private:
  void open_pair();

  SerialConfig config_;
  UniqueFd master_;
  UniqueFd peer_;
  std::string peer_path_;
};

}  // namespace epipole::hal
