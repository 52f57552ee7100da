#pragma once

#include <sys/socket.h>
#include <sys/un.h>

#include <cstdint>

#include "epipole/hal/clock.hpp"

namespace epipole::firmware {

// The service manager's notification protocol (systemd's sd_notify, Type=notify units): a
// datagram "READY=1", "STOPPING=1", "WATCHDOG=1" or "STATUS=..." to the socket named by
// $NOTIFY_SOCKET. systemd documents this protocol as stable and meant to be spoken directly,
// which keeps the firmware free of libsystemd (a dependency the cross builds would have to
// carry for one sendto()). Without $NOTIFY_SOCKET every call does nothing. Never allocates.
class ServiceNotifier {
 public:
  ServiceNotifier();  // reads $NOTIFY_SOCKET and $WATCHDOG_USEC (and $WATCHDOG_PID)
  ~ServiceNotifier();
  ServiceNotifier(const ServiceNotifier&) = delete;
  ServiceNotifier& operator=(const ServiceNotifier&) = delete;

  bool active() const { return fd_ >= 0; }
  void ready();
  void stopping();
  void status(const char* text);
  // "WATCHDOG=1", at most twice per watchdog interval (call it as often as you like).
  void watchdog();
  // The watchdog interval the service manager asked for; 0 when none.
  hal::Nanoseconds watchdog_interval() const { return watchdog_; }

 private:
  void send(const char* message);

  int fd_ = -1;
  sockaddr_un address_{};
  socklen_t address_size_ = 0;
  hal::Nanoseconds watchdog_ = 0;
  hal::Nanoseconds last_ping_ = 0;
  hal::MonotonicClock clock_;
};

}  // namespace epipole::firmware
