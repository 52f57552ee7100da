#include "epipole/firmware/thread_roles.hpp"

#include <pthread.h>
#include <sched.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstring>

#include "epipole/core/error.hpp"
#include "epipole/firmware/journal.hpp"

namespace epipole::firmware {

namespace {
std::atomic<int> g_base{0};
// Each kind of problem said once for the whole process: the maps thread's (SCHED_IDLE), then the
// real-time threads' (SCHED_FIFO), which one cannot hide the other.
std::atomic<bool> g_said_idle{false};
std::atomic<bool> g_said_realtime{false};
}  // namespace

const char* thread_name(ThreadRole role) {
  switch (role) {
    case ThreadRole::compute:
      return "epipole-work";
    case ThreadRole::link:
      return "epipole-link";
    case ThreadRole::trigger:
      return "epipole-trigger";
    case ThreadRole::snapshot:
      return "epipole-snap";
    case ThreadRole::output:
      return "epipole-out";
    case ThreadRole::maps:
      return "epipole-maps";
  }
  return "epipole";
}

void set_realtime_base(int priority) {
  g_base.store(std::clamp(priority, 0, 99));
}

int realtime_priority(ThreadRole role) {
  const int base = g_base.load();
  if (base == 0 || role == ThreadRole::snapshot || role == ThreadRole::output ||
      role == ThreadRole::maps) {
    return 0;
  }
  const int above = role == ThreadRole::trigger ? 2 : role == ThreadRole::link ? 1 : 0;
  return std::min(base + above, 99);
}

namespace {

// The calling thread's scheduling for its role; what could not be done.
std::string schedule(ThreadRole role) {
  if (role == ThreadRole::maps) {
    // Lowering a thread's scheduling needs no privilege: the rebuild only takes a core the
    // pairs leave (a pool of normal scheduling would otherwise share its cores with it).
    const sched_param param{};
    if (sched_setscheduler(0, SCHED_IDLE, &param) == 0) return {};
    return cat("the ", thread_name(role), " thread cannot use SCHED_IDLE: ", std::strerror(errno),
               " (a map rebuilt for a correction may slow the pairs meanwhile)");
  }
  // Normal scheduling is what a thread started by a real-time one gets (reset on fork), and
  // what it inherits otherwise: left as it is (a test run at idle priority stays there).
  const int priority = realtime_priority(role);
  if (priority == 0) return {};
  sched_param param{};
  param.sched_priority = priority;
  if (sched_setscheduler(0, SCHED_FIFO | SCHED_RESET_ON_FORK, &param) == 0) return {};
  return cat("threads.realtime_priority: the ", thread_name(role),
             " thread cannot use SCHED_FIFO priority ", priority, ": ", std::strerror(errno),
             " (the service needs CAP_SYS_NICE or an rtprio limit)");
}

void say_once(ThreadRole role, const std::string& problem) {
  std::atomic<bool>& said = role == ThreadRole::maps ? g_said_idle : g_said_realtime;
  if (!problem.empty() && !said.exchange(true)) {
    journal(Priority::warning, "warning: %s", problem.c_str());
  }
}

}  // namespace

std::string enter_thread_role(ThreadRole role) {
  pthread_setname_np(pthread_self(), thread_name(role));
  return schedule(role);
}

void enter_thread_role_or_say(ThreadRole role) {
  say_once(role, enter_thread_role(role));
}

void name_thread(ThreadRole role) {
  pthread_setname_np(pthread_self(), thread_name(role));
}

ScopedThreadRole::ScopedThreadRole(ThreadRole role) {
  if (realtime_priority(role) == 0) return;
  sched_param param{};
  const int policy = sched_getscheduler(0);
  if (policy < 0 || sched_getparam(0, &param) != 0) return;
  policy_ = policy;
  priority_ = param.sched_priority;
  say_once(role, schedule(role));
}

ScopedThreadRole::~ScopedThreadRole() {
  if (policy_ < 0) return;
  sched_param param{};
  param.sched_priority = priority_;
  sched_setscheduler(0, policy_, &param);
}

}  // namespace epipole::firmware
