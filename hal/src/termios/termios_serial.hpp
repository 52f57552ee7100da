#pragma once

#include "epipole/hal/serial_port.hpp"
#include "epipole/hal/unique_fd.hpp"

namespace epipole::hal {

// A serial device through termios: raw mode, 8 data bits, no parity, 1 stop bit, no flow
// control, receiver on, modem lines ignored (CLOCAL). Opening throws Error naming the device
// and the setting that failed; a device that is not there leaves the port closed (is_open()
// false), and reopen() throws DeviceMissing until it is.
class TermiosSerialPort final : public SerialPort {
 public:
  explicit TermiosSerialPort(SerialConfig config);
  ~TermiosSerialPort() override;
  TermiosSerialPort(const TermiosSerialPort&) = delete;
  TermiosSerialPort& operator=(const TermiosSerialPort&) = delete;

  IoResult read(std::span<std::byte> buffer, Nanoseconds timeout) override;
  IoResult write(std::span<const std::byte> data, Nanoseconds timeout) override;
  bool is_open() const override { return static_cast<bool>(fd_); }
  void reopen() override;
  void close() override;

  const SerialConfig& config() const { return config_; }

 private:
  void open_device();

  SerialConfig config_;
  UniqueFd fd_;
};

}  // namespace epipole::hal
