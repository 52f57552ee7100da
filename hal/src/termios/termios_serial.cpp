#include "termios/termios_serial.hpp"

#include <fcntl.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <iterator>
#include <utility>

#include "backends.hpp"
#include "device_node.hpp"
#include "epipole/core/error.hpp"
#include "epipole/hal/device_missing.hpp"
#include "epipole/hal/registry.hpp"
#include "fd_io.hpp"

namespace epipole::hal {

namespace {

struct BaudCode {
  int baud;
  speed_t code;
};

constexpr BaudCode kBauds[] = {{9600, B9600},       {19200, B19200},     {38400, B38400},
                               {57600, B57600},     {115200, B115200},   {230400, B230400},
                               {460800, B460800},   {500000, B500000},   {576000, B576000},
                               {921600, B921600},   {1000000, B1000000}, {1152000, B1152000},
                               {1500000, B1500000}, {2000000, B2000000}, {2500000, B2500000},
                               {3000000, B3000000}, {3500000, B3500000}, {4000000, B4000000}};

const BaudCode* find_baud(int baud) {
  const auto* it = std::find_if(std::begin(kBauds), std::end(kBauds),
                                [baud](const BaudCode& b) { return b.baud == baud; });
  return it == std::end(kBauds) ? nullptr : it;
}

int poll_timeout_ms(Nanoseconds timeout) {
  if (timeout <= 0) return 0;
  return static_cast<int>(std::min<Nanoseconds>((timeout + 999'999) / 1'000'000, 1'000'000'000));
}

}  // namespace

bool is_supported_baud(int baud) {
  return find_baud(baud) != nullptr;
}

TermiosSerialPort::TermiosSerialPort(SerialConfig config) : config_(std::move(config)) {
  require(!config_.device.empty(), "serial port: no device given");
  require(is_supported_baud(config_.baud), "serial port ", config_.device, ": baud rate ",
          config_.baud, " is not supported (9600 .. 4000000, standard rates)");
  try {
    open_device();
  } catch (const DeviceMissing&) {
    // Not there yet (a USB adapter at boot): closed until RecoveringSerialPort reopens it.
  }
}

TermiosSerialPort::~TermiosSerialPort() {
  close();
}

void TermiosSerialPort::open_device() {
  UniqueFd fd(detail::open_device_node(config_.device, O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC,
                                       "serial port"));
  termios tty{};
  if (tcgetattr(fd.get(), &tty) != 0) {
    const int error = errno;
    throw Error(cat("serial port ", config_.device, ": not a terminal: ", std::strerror(error)));
  }
  cfmakeraw(&tty);
  tty.c_cflag &= ~static_cast<tcflag_t>(CSTOPB | PARENB | CRTSCTS | CSIZE);
  tty.c_cflag |= CS8 | CLOCAL | CREAD;
  tty.c_cc[VMIN] = 0;
  tty.c_cc[VTIME] = 0;
  const speed_t speed = find_baud(config_.baud)->code;
  if (cfsetispeed(&tty, speed) != 0 || cfsetospeed(&tty, speed) != 0 ||
      tcsetattr(fd.get(), TCSANOW, &tty) != 0) {
    const int error = errno;
    throw Error(cat("serial port ", config_.device, ": cannot set ", config_.baud,
                    " baud 8N1 raw: ", std::strerror(error)));
  }
  // Exclusive: no other program (a getty, ModemManager, a second firmware) opens the port
  // while the firmware has it. A driver without it is used all the same.
  ioctl(fd.get(), TIOCEXCL);
  fd_ = std::move(fd);
}

void TermiosSerialPort::close() {
  fd_.reset();
}

void TermiosSerialPort::reopen() {
  close();
  open_device();
}

IoResult TermiosSerialPort::read(std::span<std::byte> buffer, Nanoseconds timeout) {
  if (!fd_) return {IoStatus::closed, 0};
  return detail::read_fd(fd_.get(), buffer, timeout);
}

IoResult TermiosSerialPort::write(std::span<const std::byte> data, Nanoseconds timeout) {
  if (!fd_) return {IoStatus::closed, 0};
  return detail::write_fd(fd_.get(), data, timeout);
}

namespace detail {

IoResult read_fd(int fd, std::span<std::byte> buffer, Nanoseconds timeout) {
  if (buffer.empty()) return {IoStatus::ok, 0};
  pollfd p{fd, POLLIN, 0};
  int ready = 0;
  do {
    ready = ::poll(&p, 1, poll_timeout_ms(timeout));
  } while (ready < 0 && errno == EINTR);
  if (ready == 0) return {IoStatus::timeout, 0};
  if (ready < 0) return {IoStatus::hung_up, 0};
  // Data that arrived before a hang-up is still delivered first.
  if ((p.revents & POLLIN) != 0) {
    const ssize_t n = ::read(fd, buffer.data(), buffer.size());
    if (n > 0) return {IoStatus::ok, static_cast<std::size_t>(n)};
    if (n < 0 && (errno == EAGAIN || errno == EINTR)) return {IoStatus::timeout, 0};
    return {IoStatus::hung_up, 0};  // end of file or EIO: the other end is gone
  }
  return {IoStatus::hung_up, 0};  // POLLHUP / POLLERR / POLLNVAL without data
}

IoResult write_fd(int fd, std::span<const std::byte> data, Nanoseconds timeout) {
  MonotonicClock clock;
  const Nanoseconds deadline = clock.now() + std::max<Nanoseconds>(timeout, 0);
  std::size_t written = 0;
  while (written < data.size()) {
    const ssize_t n = ::write(fd, data.data() + written, data.size() - written);
    if (n > 0) {
      written += static_cast<std::size_t>(n);
      continue;
    }
    if (n < 0 && errno != EAGAIN && errno != EINTR) return {IoStatus::hung_up, written};
    const Nanoseconds left = deadline - clock.now();
    if (left <= 0) return {IoStatus::timeout, written};
    pollfd p{fd, POLLOUT, 0};
    const int ready = ::poll(&p, 1, poll_timeout_ms(left));
    if (ready < 0 && errno != EINTR) return {IoStatus::hung_up, written};
    if (ready > 0 && (p.revents & (POLLHUP | POLLERR | POLLNVAL)) != 0) {
      return {IoStatus::hung_up, written};
    }
  }
  return {IoStatus::ok, written};
}

}  // namespace detail

void register_termios(BackendRegistry& registry) {
  registry.add_serial(
      "termios",
      [](const SerialConfig& config, const BackendContext&) {
        return std::unique_ptr<SerialPort>(std::make_unique<TermiosSerialPort>(config));
      },
      {.needs_device = true});
}

}  // namespace epipole::hal
