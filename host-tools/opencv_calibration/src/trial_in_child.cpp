#include "trial_in_child.hpp"

#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstring>

#include "epipole/core/error.hpp"

namespace epipole::tools {

TrialOutcome trial_in_child(const std::function<void()>& work, std::chrono::seconds limit) {
  const pid_t child = ::fork();
  if (child < 0)
    throw Error(cat("cannot start a process to try a file in: ", std::strerror(errno)));
  if (child == 0) {
    // The parent's handlers (a sanitizer's or libFuzzer's report, which would write the input as
    // a crash of this process) must not run here: a fault, or the alarm that is the time limit,
    // simply ends the child.
    for (const int fault : {SIGALRM, SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT}) {
      std::signal(fault, SIG_DFL);
    }
    ::alarm(static_cast<unsigned>(limit.count()));
    try {
      work();
    } catch (...) {
      // An exception is a result, found again when the parent runs the work itself.
    }
    ::_exit(0);  // no atexit handlers, no leak check: the child only reports that it ended
  }
  int status = 0;
  while (::waitpid(child, &status, 0) < 0) {
    if (errno != EINTR) {
      throw Error(cat("cannot wait for the process trying a file: ", std::strerror(errno)));
    }
  }
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return TrialOutcome::finished;
  if (WIFSIGNALED(status) && WTERMSIG(status) == SIGALRM) return TrialOutcome::timed_out;
  return TrialOutcome::crashed;
}

}  // namespace epipole::tools
