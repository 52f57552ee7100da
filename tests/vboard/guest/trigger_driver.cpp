// vboard-trigger: the virtual board's trigger source, run inside the guest. It waits until a
// consumer (the firmware) has requested the gpio-sim line, then pulls the line up and down at a
// fixed rate through gpio-sim's sysfs `pull` attribute, as an external trigger would, and prints
// each rising edge with the CLOCK_MONOTONIC times just before and after it was made, so the host
// can check the edge times the firmware reports. It can stop after every N edges for a while and
// start again (the trigger-loss fault).
//
//   vboard-trigger CHIP OFFSET PULL RATE_HZ [--pause-every N --pause-ms MS] [--count N]
#include <fcntl.h>
#include <linux/gpio.h>
#include <sys/ioctl.h>
#include <unistd.h>

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

bool line_used(int chip, unsigned offset) {
  gpio_v2_line_info info{};
  info.offset = offset;
  if (ioctl(chip, GPIO_V2_GET_LINEINFO_IOCTL, &info) != 0) {
    fail("line " + std::to_string(offset) +
         ": GPIO_V2_GET_LINEINFO_IOCTL: " + std::strerror(errno));
  }
  return (info.flags & GPIO_V2_LINE_FLAG_USED) != 0;
}

void pull(int fd, const char* direction, const char* path) {
  const std::size_t n = std::strlen(direction);
  if (pwrite(fd, direction, n, 0) != static_cast<ssize_t>(n)) {
    fail(std::string(path) + ": cannot write '" + direction + "': " + std::strerror(errno));
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 5)
    fail(
        "usage: vboard-trigger CHIP OFFSET PULL RATE_HZ [--pause-every N --pause-ms MS] [--count "
        "N]");
  const char* chip_path = argv[1];
  const auto offset = static_cast<unsigned>(number(argv[2], "OFFSET"));
  const char* pull_path = argv[3];
  const long rate = number(argv[4], "RATE_HZ");
  if (rate < 1 || rate > 1000) fail("RATE_HZ: " + std::to_string(rate) + " is not within 1..1000");
  long pause_every = 0, pause_ms = 0, count = 0;
  for (int i = 5; i + 1 < argc; i += 2) {
    const std::string option = argv[i];
    if (option == "--pause-every") {
      pause_every = number(argv[i + 1], "--pause-every");
    } else if (option == "--pause-ms") {
      pause_ms = number(argv[i + 1], "--pause-ms");
    } else if (option == "--count") {
      count = number(argv[i + 1], "--count");
    } else {
      fail("unknown option '" + option + "'");
    }
  }

  const int chip = open(chip_path, O_RDONLY | O_CLOEXEC);
  if (chip < 0) fail(std::string(chip_path) + ": " + std::strerror(errno));
  const int fd = open(pull_path, O_WRONLY | O_CLOEXEC);
  if (fd < 0) fail(std::string(pull_path) + ": " + std::strerror(errno));
  pull(fd, "pull-down", pull_path);
  while (!line_used(chip, offset)) sleep_until(now_ns() + 2'000'000);
  std::printf("vboard-trigger: line %u requested, %ld Hz\n", offset, rate);
  std::fflush(stdout);

  const std::int64_t period = kPerSecond / rate;
  std::int64_t next = now_ns() + period / 4;
  for (long edge = 0; count == 0 || edge < count; ++edge) {
    if (pause_every > 0 && edge > 0 && edge % pause_every == 0) {
      std::printf("vboard-trigger: pause %ld ms\n", pause_ms);
      std::fflush(stdout);
      next += pause_ms * 1'000'000;
    }
    sleep_until(next);
    const std::int64_t before = now_ns();
    pull(fd, "pull-up", pull_path);
    const std::int64_t after = now_ns();
    std::printf("vboard-trigger: edge %ld %lld %lld\n", edge, static_cast<long long>(before),
                static_cast<long long>(after));
    std::fflush(stdout);
    sleep_until(after + period / 2);
    pull(fd, "pull-down", pull_path);
    next += period;
    if (next < now_ns()) next = now_ns();  // late: the next edge at once, never a burst
  }
  return 0;
}
