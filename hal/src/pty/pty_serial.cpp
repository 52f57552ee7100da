#include "pty/pty_serial.hpp"

#include <fcntl.h>
#include <pty.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <system_error>
#include <utility>

#include "backends.hpp"
#include "epipole/core/error.hpp"
#include "epipole/hal/registry.hpp"
#include "fd_io.hpp"

namespace epipole::hal {

PtySerialPort::PtySerialPort(SerialConfig config) : config_(std::move(config)) {
  open_pair();
}

PtySerialPort::~PtySerialPort() {
  close();
  if (!config_.device.empty()) {
    std::error_code ec;
    if (std::filesystem::is_symlink(config_.device, ec))
      std::filesystem::remove(config_.device, ec);
  }
}

void PtySerialPort::open_pair() {
  int master_fd = -1;
  int peer_fd = -1;
  termios raw{};
  cfmakeraw(&raw);
  raw.c_cflag |= CLOCAL | CREAD;
  require(::openpty(&master_fd, &peer_fd, nullptr, &raw, nullptr) == 0,
          "serial port (pseudo-terminal): cannot create one: ", std::strerror(errno));
  UniqueFd master(master_fd);
  UniqueFd peer(peer_fd);
  const int flags = ::fcntl(master.get(), F_GETFL);
  char name[256] = {};
  if (flags < 0 || ::fcntl(master.get(), F_SETFL, flags | O_NONBLOCK) != 0 ||
      ::fcntl(master.get(), F_SETFD, FD_CLOEXEC) != 0 ||
      ::fcntl(peer.get(), F_SETFD, FD_CLOEXEC) != 0 ||
      ::ttyname_r(peer.get(), name, sizeof name) != 0) {
    const int error = errno;
    throw Error(cat("serial port (pseudo-terminal): cannot set it up: ", std::strerror(error)));
  }
  if (!config_.device.empty()) {
    namespace fs = std::filesystem;
    std::error_code ec;
    const fs::path link = config_.device;
    if (fs::is_symlink(link, ec)) fs::remove(link, ec);
    fs::create_symlink(name, link, ec);
    if (ec) {
      throw Error(cat("serial port ", config_.device, ": cannot link it to the pseudo-terminal ",
                      name, ": ", ec.message()));
    }
  }
  master_ = std::move(master);
  peer_ = std::move(peer);
  peer_path_ = name;
}

void PtySerialPort::close() {
  master_.reset();
  peer_.reset();
}

void PtySerialPort::reopen() {
  close();
  open_pair();
}

IoResult PtySerialPort::read(std::span<std::byte> buffer, Nanoseconds timeout) {
  if (!master_) return {IoStatus::closed, 0};
  return detail::read_fd(master_.get(), buffer, timeout);
}

IoResult PtySerialPort::write(std::span<const std::byte> data, Nanoseconds timeout) {
  if (!master_) return {IoStatus::closed, 0};
  return detail::write_fd(master_.get(), data, timeout);
}

void register_pty(BackendRegistry& registry) {
  registry.add_serial("pty",
                      [](const SerialConfig& config, const BackendContext&) {
                        return std::unique_ptr<SerialPort>(std::make_unique<PtySerialPort>(config));
                      },
                      {.simulated = true});
}

}  // namespace epipole::hal
