#pragma once

// One boot of the virtual board (docs/vboard.md) from a test: scripts/vboard/boot.sh under
// qemu-system, the firmware's link read on the host from a unix socket until the guest powers
// off, decoded with the project's own protocol decoder, and the console kept for the guest
// helpers' reports.
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "epipole/firmware/protocol/codec.hpp"

namespace epipole::test {

struct TriggerEdge {
  std::int64_t before_ns = 0;  // CLOCK_MONOTONIC of the guest just before the edge was made
  std::int64_t after_ns = 0;   // and just after
};

struct BoardRun {
  int exit_code = -1;              // boot.sh's (QEMU's): 0 when the guest powered off
  double seconds = 0;              // QEMU start to power off, host wall clock
  std::string console;             // the guest's console: kernel, init, firmware's stderr
  std::vector<std::uint8_t> link;  // every byte the firmware sent on its UART
  std::vector<protocol::DecodedMessage> messages;
  protocol::DecoderStats decoder;
  std::map<std::int64_t, TriggerEdge> edges;         // the trigger driver's edges by number
  std::map<std::int64_t, std::int64_t> frames_done;  // the left camera's completions by frame
  std::vector<std::int64_t> pauses;  // before each of the driver's pauses: its last edge's time
  int firmware_exit = -1;            // epipole-fw's exit code, as the init reports it
  std::size_t reconnected_at = 0;    // with a reconnection: the link bytes read before it

  template <typename T>
  std::vector<T> all() const {
    std::vector<T> out;
    for (const auto& m : messages) {
      if (const T* t = std::get_if<T>(&m.message)) out.push_back(*t);
    }
    return out;
  }
};

// How the firmware's link reaches the host (scripts/vboard/boot.sh, EPIPOLE_VBOARD_LINK).
enum class LinkKind {
  uart,        // a 16550: the guest cannot tell whether the host is there
  usb_serial,  // a USB serial adapter, unplugged while the host end is closed
};

// Boots ARCH ("amd64", "arm64") with INITRAMFS (scripts/vboard/prepare.sh made it) and the
// extra kernel arguments, waits at most timeout_s for the guest to power off. With
// disconnect_after_s, the host closes its end of the link that long after the first byte and
// connects again a second later (what the guest sends meanwhile is lost, as on a UART).
BoardRun boot_virtual_board(const std::string& arch, const std::string& initramfs,
                            const std::string& kernel_arguments, int timeout_s,
                            double disconnect_after_s = 0, LinkKind link = LinkKind::uart);

using Environment = std::vector<std::pair<std::string, std::string>>;

// The robot at the host's end of the link: told of each message as it arrives, it returns the
// bytes to send back (none: nothing).
using Robot = std::function<std::vector<std::uint8_t>(const protocol::DecodedMessage&)>;

// Runs a board's boot command (a script that execs QEMU) with the extra environment and its
// link on a unix socket ("socket:PATH" in the variable `link_variable`), reads the link until
// QEMU closes it, and decodes it; the console is the command's output. `name` names its files
// in the test's temporary folder. boot_virtual_board() is this with scripts/vboard/boot.sh.
BoardRun run_board(const std::vector<std::string>& command, const std::string& link_variable,
                   Environment environment, const std::string& name, int timeout_s,
                   double disconnect_after_s = 0, const Robot& robot = {});

}  // namespace epipole::test
