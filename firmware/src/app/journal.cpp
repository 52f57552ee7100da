#include "epipole/firmware/journal.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>

namespace epipole::firmware {

bool names_stream(const char* journal_stream, int fd) {
  if (journal_stream == nullptr) return false;
  unsigned long long device = 0;
  unsigned long long inode = 0;
  char rest = 0;
  if (std::sscanf(journal_stream, "%llu:%llu%c", &device, &inode, &rest) != 2) return false;
  struct stat file {};
  if (::fstat(fd, &file) != 0) return false;
  return static_cast<unsigned long long>(file.st_dev) == device &&
         static_cast<unsigned long long>(file.st_ino) == inode;
}

bool stderr_is_journal() {
  static const bool is_journal = names_stream(std::getenv("JOURNAL_STREAM"), STDERR_FILENO);
  return is_journal;
}

void journal(Priority priority, const char* format, ...) {
  char line[1024];
  constexpr int kRoom = static_cast<int>(sizeof line) - 1;  // the newline's place
  int length = 0;
  const auto advance = [&](int written) {
    if (written > 0) length = std::min(kRoom, length + written);
  };
  if (stderr_is_journal()) {
    advance(std::snprintf(line, sizeof line, "<%d>", static_cast<int>(priority)));
  }
  advance(
      std::snprintf(line + length, sizeof line - static_cast<std::size_t>(length), "epipole-fw: "));
  std::va_list args;
  va_start(args, format);
  advance(
      std::vsnprintf(line + length, sizeof line - static_cast<std::size_t>(length), format, args));
  va_end(args);
  line[length++] = '\n';
  for (int done = 0; done < length;) {
    const ssize_t n = ::write(STDERR_FILENO, line + done, static_cast<std::size_t>(length - done));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return;  // nowhere to say it
    done += static_cast<int>(n);
  }
}

bool JournalLimit::allow(std::int64_t now) {
  if (any_ && now - last_ < interval_) {
    ++left_out_;
    return false;
  }
  any_ = true;
  last_ = now;
  reported_ = left_out_;
  left_out_ = 0;
  return true;
}

}  // namespace epipole::firmware
