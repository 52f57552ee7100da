// vboard-control: sets a V4L2 control found by its name, inside the guest (the virtual board's
// init gives its two vivid cameras different test patterns with it).
//
//   vboard-control DEVICE 'CONTROL NAME' VALUE
#include <fcntl.h>
#include <linux/videodev2.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

namespace {

[[noreturn]] void fail(const std::string& what) {
  std::fprintf(stderr, "vboard-control: %s\n", what.c_str());
  std::exit(1);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 4) fail("usage: vboard-control DEVICE 'CONTROL NAME' VALUE");
  const std::string device = argv[1], name = argv[2];
  char* end = nullptr;
  const long value = std::strtol(argv[3], &end, 10);
  if (end == argv[3] || *end != '\0') fail(device + ": '" + argv[3] + "' is not a number");
  const int fd = open(device.c_str(), O_RDWR | O_CLOEXEC);
  if (fd < 0) fail(device + ": " + std::strerror(errno));

  v4l2_queryctrl query{};
  query.id = V4L2_CTRL_FLAG_NEXT_CTRL;
  while (ioctl(fd, VIDIOC_QUERYCTRL, &query) == 0) {
    if (name == reinterpret_cast<const char*>(query.name)) {
      if (value < query.minimum || value > query.maximum) {
        fail(device + ": " + name + " " + std::to_string(value) + " is outside " +
             std::to_string(query.minimum) + ".." + std::to_string(query.maximum));
      }
      v4l2_control control{query.id, static_cast<__s32>(value)};
      if (ioctl(fd, VIDIOC_S_CTRL, &control) != 0) {
        fail(device + ": " + name + ": VIDIOC_S_CTRL: " + std::strerror(errno));
      }
      close(fd);
      return 0;
    }
    query.id |= V4L2_CTRL_FLAG_NEXT_CTRL;
  }
  fail(device + ": no control named '" + name + "'");
}
