#include "epipole/firmware/service.hpp"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace epipole::firmware {

ServiceNotifier::ServiceNotifier() {
  const char* path = std::getenv("NOTIFY_SOCKET");
  if (path == nullptr || path[0] == '\0') return;
  const std::size_t length = std::strlen(path);
  if (length >= sizeof address_.sun_path || (path[0] != '/' && path[0] != '@')) return;
  address_.sun_family = AF_UNIX;
  std::memcpy(address_.sun_path, path, length);
  if (path[0] == '@') address_.sun_path[0] = '\0';  // an abstract socket
  address_size_ = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + length);
  fd_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (const char* usec = std::getenv("WATCHDOG_USEC")) {
    const char* pid = std::getenv("WATCHDOG_PID");
    const bool for_us = pid == nullptr || std::strtol(pid, nullptr, 10) == ::getpid();
    const long long us = std::strtoll(usec, nullptr, 10);
    if (for_us && us > 0) watchdog_ = static_cast<hal::Nanoseconds>(us) * 1000;
  }
}

ServiceNotifier::~ServiceNotifier() {
  if (fd_ >= 0) ::close(fd_);
}

void ServiceNotifier::send(const char* message) {
  if (fd_ < 0) return;
  // A lost notification is not worth stopping for: the watchdog pings again soon.
  [[maybe_unused]] const ssize_t n =
      ::sendto(fd_, message, std::strlen(message), MSG_NOSIGNAL,
               reinterpret_cast<const sockaddr*>(&address_), address_size_);
}

void ServiceNotifier::ready() {
  send("READY=1");
}
void ServiceNotifier::stopping() {
  send("STOPPING=1");
}

void ServiceNotifier::status(const char* text) {
  char message[256];
  std::snprintf(message, sizeof message, "STATUS=%s", text);
  send(message);
}

void ServiceNotifier::watchdog() {
  if (fd_ < 0 || watchdog_ == 0) return;
  const hal::Nanoseconds now = clock_.now();
  if (now - last_ping_ < watchdog_ / 2) return;
  last_ping_ = now;
  send("WATCHDOG=1");
}

}  // namespace epipole::firmware
