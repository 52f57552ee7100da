#pragma once

// A progress line on standard error for long work (calibrate, sim), written only when standard
// error is a terminal: each update rewrites the line, done() ends it. Nothing is written to a
// pipe or a file, so logs and --json output stay clean.
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <string>

namespace epipole::tools {

class Progress {
 public:
  explicit Progress(bool enabled = ::isatty(STDERR_FILENO) == 1) : enabled_(enabled) {}
  ~Progress() { done(); }
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  // Shows `text` (at most ten times a second unless `now`).
  void show(const std::string& text, bool now = true) {
    if (!enabled_) return;
    const auto t = std::chrono::steady_clock::now();
    if (!now && shown_ && t - last_ < std::chrono::milliseconds(100)) return;
    last_ = t;
    shown_ = true;
    std::fprintf(stderr, "\r\033[K%s", text.c_str());
    std::fflush(stderr);
  }
  void done() {
    if (!shown_) return;
    std::fprintf(stderr, "\r\033[K");
    std::fflush(stderr);
    shown_ = false;
  }

 private:
  bool enabled_;
  bool shown_ = false;
  std::chrono::steady_clock::time_point last_{};
};

}  // namespace epipole::tools
