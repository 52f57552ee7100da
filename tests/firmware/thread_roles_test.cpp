// Each of the firmware's threads takes its own scheduling (thread_roles.hpp), read back from
// /proc as a person with `ps -eLo comm,cls,rtprio` would.
#include "epipole/firmware/thread_roles.hpp"

#include <gtest/gtest.h>
#include <sched.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>

#include "epipole/firmware/firmware.hpp"
#include "epipole/firmware/trigger_watch.hpp"
#include "sim_rig.hpp"

namespace epipole::firmware {
namespace {

struct Scheduling {
  int policy = -1;
  int priority = -1;
  friend bool operator==(const Scheduling&, const Scheduling&) = default;
};

std::ostream& operator<<(std::ostream& out, const Scheduling& s) {
  return out << "policy " << s.policy << " priority " << s.priority;
}

// A thread's policy and real-time priority: fields 41 and 40 of /proc/self/task/TID/stat.
Scheduling scheduling_of(const std::filesystem::path& task) {
  std::ifstream in(task / "stat");
  std::string stat((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::istringstream fields(stat.substr(stat.rfind(')') + 2));  // from field 3 on
  std::string field;
  Scheduling s;
  for (int n = 3; fields >> field; ++n) {
    if (n == 40) s.priority = std::stoi(field);
    if (n == 41) s.policy = std::stoi(field);
  }
  return s;
}

// Every thread of this process by name (the last of a name wins).
std::map<std::string, Scheduling> threads_by_name() {
  std::map<std::string, Scheduling> out;
  for (const auto& task : std::filesystem::directory_iterator("/proc/self/task")) {
    std::ifstream comm(task.path() / "comm");
    std::string name;
    std::getline(comm, name);
    out[name] = scheduling_of(task.path());
  }
  return out;
}

// Whether this machine lets the test use SCHED_FIFO at all (root, or an rtprio limit).
bool realtime_allowed() {
  bool allowed = false;
  std::thread([&] {
    sched_param p{};
    p.sched_priority = 1;
    allowed = sched_setscheduler(0, SCHED_FIFO, &p) == 0;
  }).join();
  return allowed;
}

// Resets the process-wide base priority when the test ends.
struct RealtimeBase {
  explicit RealtimeBase(int priority) { set_realtime_base(priority); }
  ~RealtimeBase() { set_realtime_base(0); }
};

TEST(ThreadRoles, TheTriggerAboveTheLinkAboveTheComputePool) {
  {
    const RealtimeBase base(50);
    EXPECT_EQ(realtime_priority(ThreadRole::compute), 50);
    EXPECT_EQ(realtime_priority(ThreadRole::link), 51);
    EXPECT_EQ(realtime_priority(ThreadRole::trigger), 52);
    EXPECT_EQ(realtime_priority(ThreadRole::snapshot), 0);
    EXPECT_EQ(realtime_priority(ThreadRole::maps), 0);
  }
  const RealtimeBase base(98);
  EXPECT_EQ(realtime_priority(ThreadRole::trigger), 99) << "capped";
  set_realtime_base(0);
  EXPECT_EQ(realtime_priority(ThreadRole::trigger), 0) << "no real-time board: normal for all";
}

// The firmware on the simulated board with real-time priorities: read from /proc while it runs.
TEST(ThreadRoles, EachThreadRunsAtItsRolesPriority) {
  if (!realtime_allowed()) GTEST_SKIP() << "SCHED_FIFO is not allowed here (not root)";
  test::SimRig rig(64, 32, 4);
  BoardConfig config =
      rig.parse("threads: {count: 2, realtime_priority: 10}\nsnapshot_directory: snapshots\n");
  config.serial.backend = "pty";
  const std::vector<std::string> problems = apply_scheduling(config.threads);
  EXPECT_TRUE(problems.empty());
  const RealtimeBase reset(10);
  Firmware fw(rig.replaying(config));
  const auto before = sched_getscheduler(0);
  std::map<std::string, Scheduling> seen;
  Scheduling loop{}, started_by_loop{};
  std::atomic<bool> stop{false};
  struct Observer : FrameObserver {
    std::function<void()> at_frame_5;
    int frames = 0;
    void on_frame(const FrameResult&) override {
      if (++frames == 5) at_frame_5();
    }
  } observer;
  observer.at_frame_5 = [&] {
    seen = threads_by_name();
    sched_param p{};
    sched_getparam(0, &p);
    loop = {sched_getscheduler(0), p.sched_priority};
    std::thread([&] {  // a thread the loop starts (as libcamera does): not real-time
      sched_param q{};
      sched_getparam(0, &q);
      started_by_loop = {sched_getscheduler(0), q.sched_priority};
    })
        .join();
  };
  fw.frame_loop().set_observer(&observer);
  fw.run(10, stop);
  EXPECT_EQ(loop, (Scheduling{SCHED_FIFO | SCHED_RESET_ON_FORK, 10})) << "the frame loop";
  EXPECT_EQ(started_by_loop, (Scheduling{SCHED_OTHER, 0}));
  EXPECT_EQ(seen["epipole-work"], (Scheduling{SCHED_FIFO, 10})) << "the compute pool's worker";
  EXPECT_EQ(seen["epipole-link"], (Scheduling{SCHED_FIFO, 11}));
  EXPECT_EQ(seen["epipole-snap"], (Scheduling{SCHED_OTHER, 0}));
  EXPECT_EQ(sched_getscheduler(0), before) << "the caller's scheduling given back";
}

// A line that fires an edge every 5 ms.
class SteadyLine final : public hal::TriggerLine {
 public:
  const hal::TriggerConfig& config() const override { return config_; }
  void start() override {}
  void stop() override {}
  hal::EdgeResult wait_edge(hal::Nanoseconds) override {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    return {hal::EdgeStatus::ok, {}};
  }
  void set_rate(double) override {}

 private:
  hal::TriggerConfig config_;
};

TEST(ThreadRoles, TheTriggerThreadRunsAboveTheLink) {
  if (!realtime_allowed()) GTEST_SKIP() << "SCHED_FIFO is not allowed here (not root)";
  const RealtimeBase base(10);
  SteadyLine line;
  TriggerWatch watch(line, 5'000'000);
  watch.start();
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  const std::map<std::string, Scheduling> seen = threads_by_name();
  watch.stop();
  ASSERT_EQ(seen.count("epipole-trigger"), 1u);
  EXPECT_EQ(seen.at("epipole-trigger"), (Scheduling{SCHED_FIFO, 12}));
}

}  // namespace
}  // namespace epipole::firmware
