// vboard-trigger: the virtual board's trigger source, run inside the guest. vivid's cameras have
// no trigger input and run free, so the trigger follows them: the driver reads the left camera's
// frame completions from the kernel's trace events (tracefs, on the CLOCK_MONOTONIC trace clock,
// enabled before the camera streams): vb2_buf_done gives a buffer's completion time, and the
// v4l2_dqbuf of the same buffer, when the firmware takes it, its frame's sequence number. Counting
// completions is not enough: vivid numbers its frames by the time since it started streaming, so
// when its thread runs late (an emulated CPU on a loaded host) it skips the numbers of the frames
// it missed. The driver makes each next frame's edge half a period before it is due, pulling the
// gpio-sim line up and down through its sysfs `pull` attribute, so edge N comes half a period
// before frame N, as on a board whose cameras expose on the edge (the firmware pairs each frame
// with the edge at its time). The edges of frames it is behind on (after a pause, or read late)
// are not made: the next edge is the next frame's, and its number says so. It prints each edge
// with the CLOCK_MONOTONIC
// times just before and after it was made, and each completion it read, for the host to check the
// edge times the firmware reports. It can stop after every N edges for a while and start again (the
// trigger-loss fault), and make glitches at given edges: a bounce (a second rising edge right after
// edge N, as fast as the line can be pulled down and up again), a missed edge (frame N gets none),
// a late edge (edge N made MS milliseconds after it was due).
//
//   vboard-trigger CHIP OFFSET PULL TRACE_PIPE RATE_HZ CAMERA [--pause-every N --pause-ms MS]
//                  [--bounce-at N] [--miss-at N] [--late-at N:MS]
//
// CAMERA: the left camera's device node (its minor number picks its v4l2_dqbuf events).
#include <fcntl.h>
#include <linux/gpio.h>
#include <sys/ioctl.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <string>

namespace {

constexpr std::int64_t kPerSecond = 1'000'000'000;

std::int64_t now_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * kPerSecond + ts.tv_nsec;
}

void sleep_until(std::int64_t t) {
  const timespec ts{static_cast<time_t>(t / kPerSecond), static_cast<long>(t % kPerSecond)};
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

[[noreturn]] void fail(const std::string& what) {
  std::fprintf(stderr, "vboard-trigger: %s\n", what.c_str());
  std::exit(1);
}

long number(const char* text, const char* what) {
  char* end = nullptr;
  errno = 0;
  const long v = std::strtol(text, &end, 10);
  if (errno != 0 || end == text || *end != '\0' || v < 0) {
    fail(std::string(what) + ": '" + text + "' is not a number >= 0");
  }
  return v;
}

// The consumer that requested the line, or nothing while it is free.
std::string line_consumer(int chip, unsigned offset) {
  gpio_v2_line_info info{};
  info.offset = offset;
  if (ioctl(chip, GPIO_V2_GET_LINEINFO_IOCTL, &info) != 0) {
    fail("line " + std::to_string(offset) +
         ": GPIO_V2_GET_LINEINFO_IOCTL: " + std::strerror(errno));
  }
  if ((info.flags & GPIO_V2_LINE_FLAG_USED) == 0) return {};
  return std::string(info.consumer, strnlen(info.consumer, sizeof info.consumer));
}

// Whether an interrupt handler named `name` is installed: the kernel names a line's edge
// interrupt after its consumer once it has set it up, which it does after the line shows as used.
bool interrupt_installed(const std::string& name) {
  FILE* interrupts = std::fopen("/proc/interrupts", "r");
  if (interrupts == nullptr) fail(std::string("/proc/interrupts: ") + std::strerror(errno));
  std::array<char, 512> text{};
  bool found = false;
  while (!found && std::fgets(text.data(), text.size(), interrupts) != nullptr) {
    found = std::strstr(text.data(), name.c_str()) != nullptr;
  }
  std::fclose(interrupts);
  return found;
}

void pull(int fd, const char* direction, const char* path) {
  const std::size_t n = std::strlen(direction);
  if (pwrite(fd, direction, n, 0) != static_cast<ssize_t>(n)) {
    fail(std::string(path) + ": cannot write '" + direction + "': " + std::strerror(errno));
  }
}

// The value after "NAME = " in a trace event's fields (from `fields`), or -1.
long long field(const char* fields, const char* name) {
  const std::string key = std::string(name) + " = ";
  const char* at = std::strstr(fields, key.c_str());
  return at == nullptr ? -1 : std::strtoll(at + key.size(), nullptr, 10);
}

// One "vivid-000-vid-c-PID [CPU] FLAGS TIME: vb2_buf_done: ... index = I ..." line of the trace:
// buffer I of the first vivid instance (the left camera) completed at TIME.
bool parse_done(const char* line, long& index, std::int64_t& time_ns) {
  const char* event = std::strstr(line, ": vb2_buf_done: ");
  const char* task = std::strstr(line, "vivid-000-vid-c-");
  if (event == nullptr || task == nullptr || task > event) return false;
  index = static_cast<long>(field(event, "index"));
  const char* start = event;
  while (start > line && start[-1] != ' ') --start;
  time_ns = static_cast<std::int64_t>(std::strtod(start, nullptr) * 1e9);
  return index >= 0;
}

// One "...: v4l2_dqbuf: minor = M, index = I, ..., flags = F, ..., sequence = S" line: the
// firmware took buffer I of the device of minor M, holding frame S (false for another device);
// `error`: the buffer holds no frame (flag ERROR: the camera stopped under it).
bool parse_dequeued(const char* line, long device_minor, long& index, long& sequence, bool& error) {
  const char* event = std::strstr(line, ": v4l2_dqbuf: ");
  if (event == nullptr || field(event, "minor") != device_minor) return false;
  index = static_cast<long>(field(event, "index"));
  sequence = static_cast<long>(field(event, "sequence"));
  const char* flags = std::strstr(event, "flags = ");
  const char* flags_end = flags == nullptr ? nullptr : std::strchr(flags, ',');
  const char* error_flag = std::strstr(event, "ERROR");
  error = error_flag != nullptr && (flags_end == nullptr || error_flag < flags_end);
  return index >= 0 && sequence >= 0;
}

class Line {
 public:
  explicit Line(const char* pull_path) : path_(pull_path) {
    fd_ = open(pull_path, O_WRONLY | O_CLOEXEC);
    if (fd_ < 0) fail(std::string(pull_path) + ": " + std::strerror(errno));
    pull(fd_, "pull-down", path_);
  }
  // A 1 ms pulse: the rising edge is the trigger. With `bounce`, the line drops and rises again
  // at once after it: a second rising edge some hundred microseconds later, which is no trigger.
  void pulse(bool bounce = false) {
    const std::int64_t before = now_ns();
    pull(fd_, "pull-up", path_);
    const std::int64_t after = now_ns();
    std::printf("vboard-trigger: edge %ld %lld %lld\n", edges_++, static_cast<long long>(before),
                static_cast<long long>(after));
    ++pulses_;
    if (bounce) {
      pull(fd_, "pull-down", path_);
      const std::int64_t bounced = now_ns();
      pull(fd_, "pull-up", path_);
      std::printf("vboard-trigger: bounce %ld %lld %lld\n", edges_ - 1,
                  static_cast<long long>(bounced), static_cast<long long>(now_ns()));
    }
    std::fflush(stdout);
    sleep_until(after + 1'000'000);
    pull(fd_, "pull-down", path_);
    sleep_until(now_ns() + 1'000'000);
  }
  long edges() const { return edges_; }
  long pulses() const { return pulses_; }
  // The frames before `number` are done without an edge: the next edge is `number`'s.
  void skip_to(long number) { edges_ = std::max(edges_, number); }

 private:
  const char* path_;
  int fd_ = -1;
  long edges_ = 0;   // the number of the next edge
  long pulses_ = 0;  // the edges made
};

}  // namespace

int main(int argc, char** argv) {
  if (argc < 7) {
    fail(
        "usage: vboard-trigger CHIP OFFSET PULL TRACE_PIPE RATE_HZ CAMERA [--pause-every N "
        "--pause-ms MS] [--bounce-at N] [--miss-at N] [--late-at N:MS]");
  }
  const char* chip_path = argv[1];
  const auto offset = static_cast<unsigned>(number(argv[2], "OFFSET"));
  const char* trace_path = argv[4];
  const long rate = number(argv[5], "RATE_HZ");
  if (rate < 1 || rate > 1000) fail("RATE_HZ: " + std::to_string(rate) + " is not within 1..1000");
  struct stat camera {};
  if (stat(argv[6], &camera) != 0) fail(std::string(argv[6]) + ": " + std::strerror(errno));
  const auto camera_minor = static_cast<long>(minor(camera.st_rdev));
  long pause_every = 0, pause_ms = 0;
  long bounce_at = -1, miss_at = -1, late_at = -1, late_ms = 0;
  for (int i = 7; i < argc; i += 2) {
    const std::string option = argv[i];
    if (i + 1 >= argc) fail("option '" + option + "' needs a value");
    std::string value = argv[i + 1];
    if (option == "--pause-every") {
      pause_every = number(value.c_str(), "--pause-every");
    } else if (option == "--pause-ms") {
      pause_ms = number(value.c_str(), "--pause-ms");
    } else if (option == "--bounce-at") {
      bounce_at = number(value.c_str(), "--bounce-at");
    } else if (option == "--miss-at") {
      miss_at = number(value.c_str(), "--miss-at");
    } else if (option == "--late-at") {
      const std::size_t colon = value.find(':');
      if (colon == std::string::npos) fail("--late-at: '" + value + "' is not N:MS");
      late_ms = number(value.substr(colon + 1).c_str(), "--late-at MS");
      value.resize(colon);
      late_at = number(value.c_str(), "--late-at N");
    } else {
      fail("unknown option '" + option + "'");
    }
  }

  const int chip = open(chip_path, O_RDONLY | O_CLOEXEC);
  if (chip < 0) fail(std::string(chip_path) + ": " + std::strerror(errno));
  FILE* trace = std::fopen(trace_path, "r");
  if (trace == nullptr) fail(std::string(trace_path) + ": " + std::strerror(errno));
  Line line(argv[3]);
  std::string consumer;
  while ((consumer = line_consumer(chip, offset)).empty()) sleep_until(now_ns() + 2'000'000);
  // The line shows as used before its edge interrupt is set up, in the same request: an edge
  // then goes unseen, and the firmware's numbers of every later edge are one behind the frames'.
  // On an emulated CPU of a loaded host that gap lasted more than 20 ms.
  const std::int64_t requested = now_ns();
  while (!interrupt_installed(consumer)) {
    if (now_ns() - requested > 10 * kPerSecond) {
      fail("line " + std::to_string(offset) + " requested by '" + consumer +
           "', but no interrupt of that name in /proc/interrupts after 10 s");
    }
    sleep_until(now_ns() + 2'000'000);
  }
  std::printf("vboard-trigger: line %u requested by %s, following the left camera at %ld Hz\n",
              offset, consumer.c_str(), rate);
  std::fflush(stdout);
  // Frame 0's edge: the cameras started streaming just before the line was requested, and
  // their first frame comes about a period later.
  line.pulse();

  const std::int64_t period = kPerSecond / rate;
  std::int64_t resume = 0;
  long paused_at = 0;
  std::array<char, 1024> text{};
  std::array<std::int64_t, 64> done_at{};  // by buffer index: its completion not yet taken
  long sequence = -1;                      // the last frame followed
  long last_taken = -1;                    // vivid's number of it
  long base = 0;                           // what vivid's numbers are counted from
  while (std::fgets(text.data(), text.size(), trace) != nullptr) {
    long index = 0;
    std::int64_t completed = 0;
    if (parse_done(text.data(), index, completed)) {
      if (index < static_cast<long>(done_at.size())) {
        done_at[static_cast<std::size_t>(index)] = completed;
      }
      continue;
    }
    long taken = 0;
    bool error = false;
    if (!parse_dequeued(text.data(), camera_minor, index, taken, error) ||
        index >= static_cast<long>(done_at.size())) {
      continue;
    }
    const std::int64_t done = done_at[static_cast<std::size_t>(index)];
    done_at[static_cast<std::size_t>(index)] = 0;
    if (error || done == 0) continue;
    // vivid loaded again counts from 0 again; its frames go on after the last one here, as the
    // firmware's edges do.
    if (taken < last_taken) base = sequence + 1;
    last_taken = taken;
    if (base + taken <= sequence) continue;
    sequence = base + taken;
    std::printf("vboard-trigger: frame %ld %lld\n", sequence, static_cast<long long>(done));
    if (now_ns() < resume) continue;
    if (pause_every > 0 && line.pulses() > 0 && line.pulses() % pause_every == 0 &&
        paused_at != line.pulses()) {
      paused_at = line.pulses();
      resume = now_ns() + pause_ms * 1'000'000;
      std::printf("vboard-trigger: pause %ld ms\n", pause_ms);
      std::fflush(stdout);
      continue;
    }
    line.skip_to(sequence + 1);  // behind: no edge for a frame already done
    const long next = line.edges();
    if (next == miss_at) {  // the frame comes, its edge does not
      std::printf("vboard-trigger: missed %ld\n", next);
      std::fflush(stdout);
      line.skip_to(next + 1);
      continue;
    }
    // The next frame's edge, half a period early (a late one, later).
    sleep_until(done + period / 2 + (next == late_at ? late_ms * 1'000'000 : 0));
    if (next == late_at) std::printf("vboard-trigger: late %ld %ld ms\n", next, late_ms);
    line.pulse(next == bounce_at);
  }
  fail(std::string(trace_path) + ": the trace ended");
}
