#pragma once

#include <cstdint>

namespace epipole::firmware {

// The syslog priorities of the firmware's lines (sd-daemon(3)).
enum class Priority { error = 3, warning = 4, notice = 5, info = 6 };

// One line for the operator on standard error: "epipole-fw: " and the formatted text. When
// standard error is the journal (systemd sets JOURNAL_STREAM to its device and inode,
// systemd.exec(5)), the line starts with its priority, "<4>", which journald takes off and keeps,
// so `journalctl -p warning -u epipole` lists the warnings and errors; on a terminal or in a file
// the line is plain. One write(2) per line, so the lines of several threads do not mix; a line
// longer than 1 KiB is cut. Never allocates: the frame loop's threads call it.
void journal(Priority priority, const char* format, ...) __attribute__((format(printf, 2, 3)));

// At most one line per interval from one source that a peer can drive (a robot that sends
// refused commands in a loop): the lines in between are left out and counted, and the next line
// written says how many. Never allocates.
class JournalLimit {
 public:
  explicit JournalLimit(std::int64_t interval_ns) : interval_(interval_ns) {}
  // Whether a line may be written at `now` (any steady clock, in ns). When it may,
  // left_out() is the number of lines not written since the last one.
  bool allow(std::int64_t now);
  std::uint64_t left_out() const { return reported_; }

 private:
  std::int64_t interval_;
  std::int64_t last_ = 0;
  bool any_ = false;
  std::uint64_t left_out_ = 0;
  std::uint64_t reported_ = 0;
};

// The two lines of a fault that comes and goes (a device lost, then back): a fault that flaps is
// said at most once an interval, its end only when its start was, and the next start said
// knows how many were left out. Never allocates.
class JournalEpisodes {
 public:
  explicit JournalEpisodes(std::int64_t interval_ns) : limit_(interval_ns) {}
  // The fault began at `now`: whether to say so (and, later, that it ended).
  bool begins(std::int64_t now) {
    said_ = limit_.allow(now);
    return said_;
  }
  bool end_is_said() const { return said_; }
  // When begins() said yes: the episodes not said since the last one that was.
  std::uint64_t left_out() const { return limit_.left_out(); }

 private:
  JournalLimit limit_;
  bool said_ = false;
};

// Whether standard error is the journal's stream (decided at the first line).
bool stderr_is_journal();

// Whether a JOURNAL_STREAM value ("device:inode") names the file open on `fd`.
bool names_stream(const char* journal_stream, int fd);

}  // namespace epipole::firmware
