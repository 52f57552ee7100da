#pragma once

#include <string>

namespace epipole::firmware {

// What a thread of the firmware does, which decides its scheduling on a board that asks for
// real-time priorities (threads.realtime_priority P): the trigger's thread above the link's,
// the link's above the frame loop and its compute pool, so that a saturated frame rate can
// neither stretch the trigger's pulses nor hold up the robot's commands; file writes at normal
// priority. docs/firmware.md, "Threads".
enum class ThreadRole {
  compute,   // the frame loop and its worker pool: SCHED_FIFO P
  link,      // the serial link: SCHED_FIFO P + 1
  trigger,   // the trigger line (a master fires its pulses from it): SCHED_FIFO P + 2
  snapshot,  // snapshot files: normal scheduling
  output,    // an output's own work (a recording, a network): normal scheduling
  maps,      // rectification maps rebuilt for a corrected rig: SCHED_IDLE, in the time the
             // pairs leave (never delaying one), whatever the board asks
};

const char* thread_name(ThreadRole role);  // "epipole-work", ... (top -H, /proc/PID/task)

// The priority the threads start from (0: normal scheduling for all). Set once at start-up,
// before the firmware's threads start.
void set_realtime_base(int priority);
int realtime_priority(ThreadRole role);  // 0: normal scheduling

// Names the calling thread after its role and gives it its scheduling (a role of normal
// scheduling keeps what the thread has). Real-time threads are set to reset on fork: the threads
// they start (libcamera's own, for one) begin at normal scheduling, not at theirs. Returns what
// could not be done (empty: all of it); the firmware says it once in the journal.
std::string enter_thread_role(ThreadRole role);

// Calls enter_thread_role() and says a problem in the journal, once for the whole process.
void enter_thread_role_or_say(ThreadRole role);
// Names the calling thread after its role only; its scheduling stays as it is.
void name_thread(ThreadRole role);

// The calling thread (the frame loop's: the process's main thread, whose name is the program's)
// scheduled as `role` for the object's life, unnamed; its scheduling as it was afterwards.
class ScopedThreadRole {
 public:
  explicit ScopedThreadRole(ThreadRole role);
  ~ScopedThreadRole();
  ScopedThreadRole(const ScopedThreadRole&) = delete;
  ScopedThreadRole& operator=(const ScopedThreadRole&) = delete;

 private:
  int policy_ = -1;  // -1: nothing changed
  int priority_ = 0;
};

}  // namespace epipole::firmware
