// epipole-fw as a process, as the service manager runs it: one-line errors, SIGTERM, the
// notification socket and its watchdog, the link's stream complete after a stop.
#include <fcntl.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <chrono>
#include <fstream>
#include <iterator>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "epipole/core/image_io.hpp"
#include "epipole/firmware/protocol/codec.hpp"
#include "epipole/hal/serial_port.hpp"
#include "loopback.hpp"
#include "pty/pty_serial.hpp"
#include "sim_rig.hpp"
#include "termios/termios_serial.hpp"
#include "test_clients.hpp"
#include "test_paths.hpp"

namespace epipole::firmware {
namespace {

using Clock = std::chrono::steady_clock;

struct Process {
  pid_t pid = -1;
  int output = -1;  // stderr and stdout
};

// The firmware with its output in a pipe; `as_service`: the pipe is its journal stream, as
// systemd makes standard error (JOURNAL_STREAM names the pipe's device and inode).
Process start(const std::vector<std::string>& args, std::vector<std::string> env = {},
              bool as_service = false) {
  int pipe_fds[2];
  if (::pipe(pipe_fds) != 0) throw std::runtime_error("pipe");
  if (as_service) {
    struct stat pipe_file {};
    ::fstat(pipe_fds[1], &pipe_file);
    env.push_back("JOURNAL_STREAM=" + std::to_string(pipe_file.st_dev) + ":" +
                  std::to_string(pipe_file.st_ino));
  }
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::dup2(pipe_fds[1], 1);
    ::dup2(pipe_fds[1], 2);
    ::close(pipe_fds[0]);
    for (const std::string& e : env) ::putenv(const_cast<char*>(e.c_str()));
    std::vector<char*> argv;
    argv.push_back(const_cast<char*>(test::firmware_path()));
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv(test::firmware_path(), argv.data());
    ::_exit(127);
  }
  ::close(pipe_fds[1]);
  return {pid, pipe_fds[0]};
}

// Waits for the process and returns its exit code and output.
std::pair<int, std::string> finish(const Process& p) {
  std::string out;
  char buffer[4096];
  ssize_t n = 0;
  while ((n = ::read(p.output, buffer, sizeof buffer)) > 0)
    out.append(buffer, static_cast<std::size_t>(n));
  ::close(p.output);
  int status = 0;
  ::waitpid(p.pid, &status, 0);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status), out};
}

// A board folder with image files and a link at a known path.
struct BoardFolder {
  test::SimRig rig;
  std::filesystem::path link;
  BoardFolder() {
    const hal::StereoImages images = rig.images(2);
    for (int i = 0; i < 2; ++i) {
      save_image(rig.dir.path() / ("left" + std::to_string(i) + ".png"),
                 GrayView(images.left[static_cast<std::size_t>(i)].view()));
      save_image(rig.dir.path() / ("right" + std::to_string(i) + ".png"),
                 GrayView(images.right[static_cast<std::size_t>(i)].view()));
    }
    link = rig.dir.path() / "link";
    std::string text = rig.yaml();
    text.replace(text.find("serial: {backend: none}"), 23,
                 "serial: {backend: pty, device: " + link.string() + "}");
    text.replace(text.find("synthesize: unused.png, disparity: 8"), 36,
                 "left: left*.png, right: right*.png");
    text.replace(text.find("charge_compute: false"), 21, "charge_compute: true");
    std::ofstream(rig.dir.path() / "board.yaml") << text;
  }
  std::string path() const { return rig.dir.path().string(); }
};

TEST(EpipoleFw, BadConfigurationIsOneLineAndExitCodeOne) {
  BoardFolder board;
  const auto [code, out] = finish(start({"--board", board.path() + "/nothing"}));
  EXPECT_EQ(code, 1);
  EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << out;
  EXPECT_NE(out.find("nothing"), std::string::npos) << out;

  std::ofstream(board.rig.dir.path() / "bad.yaml") << board.rig.yaml("colour: blue\n");
  const auto [code2, out2] = finish(start({"--board", board.path() + "/bad.yaml"}));
  EXPECT_EQ(code2, 1);
  EXPECT_NE(out2.find("bad.yaml: unknown key 'colour'"), std::string::npos) << out2;

  const auto [code3, out3] = finish(start({"--board", board.path(), "--scene", "elsewhere"}));
  EXPECT_EQ(code3, 1);
  EXPECT_NE(out3.find("'elsewhere' is not a scene of this board"), std::string::npos) << out3;

  const auto [code4, out4] = finish(start({"--frames", "x"}));
  EXPECT_NE(code4, 0);
}

// Cameras and a serial adapter that are not there when the firmware starts (USB devices slower
// than the service at boot) are waited for, said once in the journal, and no reason to exit.
// The live view of epipole-fw itself, as Foxglove and Lichtblick connect to it: Foxglove's own
// client (tests/clients/foxglove-view.mjs) subscribes to every channel it advertises and
// decodes messages on each (the values are checked against the pipeline's in
// ViewOutput.FoxglovesClientGetsEveryChannelAsThePipelineComputedIt).
TEST(EpipoleFw, FoxglovesClientTakesEveryChannelOfItsLiveView) {
  ASSERT_TRUE(test::clients_installed()) << "the test clients are not installed: scripts/setup.sh";
  BoardFolder board;
  firmware::BoardConfig with_cascade = board.rig.config;
  board.rig.add_cascade(with_cascade);  // writes cascade.bin beside the board file
  const int port = test::free_port();
  std::ifstream file(board.rig.dir.path() / "board.yaml");
  std::string text{std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>()};
  text.replace(text.find("detect: false"), 13, "detect: true");
  text += "outputs: {view: {port: " + std::to_string(port) +
          "}}\ndetector: {cascade: cascade.bin, min_size: 20}\n";
  std::ofstream(board.rig.dir.path() / "view.yaml") << text;
  const Process p = start({"--board", (board.rig.dir.path() / "view.yaml").string()});
  ASSERT_TRUE(test::listening(port));
  const test::ToolResult got =
      test::run_client("foxglove-view.mjs", "ws://127.0.0.1:" + std::to_string(port) + "/ 3 2");
  ::kill(p.pid, SIGTERM);
  const auto [code, out] = finish(p);
  EXPECT_EQ(code, 0) << out;
  ASSERT_EQ(got.exit_code, 0) << got.out;
  const nlohmann::json taken = nlohmann::json::parse(got.out);
  EXPECT_EQ(taken["protocol"], "foxglove.websocket.v1");
  EXPECT_EQ(taken["channels"].size(), 11u);
  std::map<std::string, int> counts;
  for (const nlohmann::json& m : taken["messages"]) ++counts[m["topic"].get<std::string>()];
  for (const nlohmann::json& c : taken["channels"]) {
    EXPECT_GE(counts[c["topic"].get<std::string>()], 1) << c["topic"];
  }
}

TEST(EpipoleFw, DevicesNotThereAtStartAreWaitedFor) {
  const test::TempDir dir;
  std::ofstream(dir.path() / "board.yaml")
      << "version: 1\nname: late-devices\n"
         "cameras: {backend: v4l2, left: /dev/video-epipole-late-0, right: "
         "/dev/video-epipole-late-1, width: 160, height: 96, trigger: free_running}\n"
         "trigger: {backend: none}\n"
         "serial: {backend: termios, device: "
      << (dir.path() / "tty-late").string() << ", baud: 115200}\n";
  const Process p = start({"--board", (dir.path() / "board.yaml").string()});
  // The serial device appears half a second later (a USB adapter enumerated after the service
  // started): a pseudo-terminal, whose terminal end the board file's path comes to name.
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  hal::PtySerialPort robot({});
  std::filesystem::create_symlink(robot.peer_path(), dir.path() / "tty-late");
  std::this_thread::sleep_for(std::chrono::milliseconds(3000));  // back-off 0.1 s doubling
  ::kill(p.pid, SIGTERM);
  const auto [code, out] = finish(p);
  EXPECT_EQ(code, 0) << out;
  const std::string serial = "serial port " + (dir.path() / "tty-late").string();
  const std::size_t waiting = out.find(serial + " is not there yet: waiting for it");
  EXPECT_NE(waiting, std::string::npos) << out;
  EXPECT_NE(out.find(serial + " open", waiting), std::string::npos) << out;
  for (const char* camera : {"/dev/video-epipole-late-0", "/dev/video-epipole-late-1"}) {
    EXPECT_NE(out.find(std::string("camera ") + camera + ": not there (yet)"), std::string::npos)
        << out;
  }
  EXPECT_NE(out.find("stopped after 0 pairs"), std::string::npos) << out;
}

TEST(EpipoleFw, CheckPrintsTheMemoryPerStageOpeningNoDevice) {
  const test::TempDir dir;
  const std::string board =
      "version: 1\nname: check-me\n"
      "cameras: {backend: v4l2, left: /dev/video-epipole-none-0, right: "
      "/dev/video-epipole-none-1, width: 320, height: 240, trigger: external, timeout_ms: 100}\n"
      "trigger: {backend: gpiod, line: EPIPOLE_NO_SUCH_LINE, rate_hz: 30}\n"
      "serial: {backend: termios, device: /dev/tty-epipole-none, baud: 115200}\n"
      "stereo: {max_disparity: 64}\n";
  std::ofstream(dir.path() / "board.yaml") << board;
  const auto [code, out] =
      finish(start({"--board", (dir.path() / "board.yaml").string(), "--check"}));
  EXPECT_EQ(code, 0) << out;
  EXPECT_NE(out.find("board check-me, 320x240, valid"), std::string::npos) << out;
  for (const char* part : {"corners", "disparity", "sparse", "link", "frame loop", "total"}) {
    EXPECT_NE(out.find(std::string("  ") + part), std::string::npos) << part << "\n" << out;
  }
  EXPECT_EQ(out.find("not there"), std::string::npos) << "no device was opened:\n" << out;
  EXPECT_EQ(out.find("  cameras"), std::string::npos) << "the stand-ins are not the board's\n"
                                                      << out;

  std::ofstream(dir.path() / "small.yaml") << board << "memory_budget_mb: 0.5\n";
  const auto [over, said] =
      finish(start({"--board", (dir.path() / "small.yaml").string(), "--check"}));
  EXPECT_EQ(over, 1) << said;
  EXPECT_NE(said.find("memory_budget_mb: the frame loop needs"), std::string::npos) << said;
}

// Under systemd each line carries its priority, so `journalctl -p warning` finds the warnings
// and errors; on a terminal or in a file (JOURNAL_STREAM absent or naming another file) the
// lines are plain.
TEST(EpipoleFw, LinesCarryTheirPriorityWhenStandardErrorIsTheJournal) {
  BoardFolder board;
  const auto [code, out] = finish(start({"--board", board.path(), "--frames", "3"}, {}, true));
  EXPECT_EQ(code, 0) << out;
  EXPECT_EQ(out.rfind("<6>epipole-fw: board ", 0), 0u) << out;
  EXPECT_NE(out.find("\n<6>epipole-fw: stopped after 3 pairs"), std::string::npos) << out;
  std::size_t lines = 0;
  for (std::size_t at = 0; at < out.size(); at = out.find('\n', at) + 1, ++lines) {
    EXPECT_TRUE(out.compare(at, 1, "<") == 0) << "every line: " << out.substr(at, 60);
    if (out.find('\n', at) == std::string::npos) break;
  }
  EXPECT_GE(lines, 2u);

  const auto [bad_code, bad] =
      finish(start({"--board", board.path() + "/nothing"}, {}, /*as_service=*/true));
  EXPECT_EQ(bad_code, 1);
  EXPECT_EQ(bad.rfind("<3>epipole-fw: ", 0), 0u) << bad;

  std::ifstream board_file(board.rig.dir.path() / "board.yaml");
  std::string fresh_board((std::istreambuf_iterator<char>(board_file)),
                          std::istreambuf_iterator<char>());
  fresh_board.replace(fresh_board.find("calibration: rig.yaml"), 21,
                      "calibration: rig-not-made-yet.yaml");
  std::ofstream(board.rig.dir.path() / "uncalibrated.yaml") << fresh_board;
  const auto [fresh_code, fresh] =
      finish(start({"--board", board.path() + "/uncalibrated.yaml", "--frames", "2"}, {}, true));
  EXPECT_EQ(fresh_code, 0) << fresh;
  EXPECT_NE(fresh.find("<4>epipole-fw: not calibrated: "), std::string::npos) << fresh;

  const auto [plain_code, plain] = finish(start({"--board", board.path(), "--frames", "3"},
                                                {"JOURNAL_STREAM=1:1"}, /*as_service=*/false));
  EXPECT_EQ(plain_code, 0) << plain;
  EXPECT_EQ(plain.find('<'), std::string::npos) << "not the journal: plain lines\n" << plain;
  EXPECT_EQ(plain.rfind("epipole-fw: board ", 0), 0u) << plain;
}

TEST(EpipoleFw, RunsTheGivenNumberOfFrames) {
  BoardFolder board;
  const auto [code, out] = finish(start({"--board", board.path(), "--frames", "25"}));
  EXPECT_EQ(code, 0) << out;
  EXPECT_NE(out.find("stopped after 25 pairs"), std::string::npos) << out;
}

TEST(EpipoleFw, StopsCleanlyOnSigtermWithTheLinkComplete) {
  BoardFolder board;
  const Process p = start({"--board", board.path()});
  // The robot's end: wait for the firmware to make it, then read everything.
  const auto deadline = Clock::now() + std::chrono::seconds(20);
  while (!std::filesystem::exists(board.link) && Clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ASSERT_TRUE(std::filesystem::exists(board.link)) << finish(p).second;
  hal::TermiosSerialPort robot({board.link.string(), 115200});
  protocol::FrameDecoder decoder;
  std::array<std::byte, 4096> buffer{};
  // True when the firmware closed its end (the robot sees the hang-up).
  const auto read_for = [&](std::chrono::milliseconds span) {
    const auto until = Clock::now() + span;
    while (Clock::now() < until) {
      const hal::IoResult r = robot.read(buffer, 50'000'000);
      if (r.status == hal::IoStatus::hung_up) return true;
      for (std::size_t i = 0; i < r.bytes; ++i) decoder.push(static_cast<std::uint8_t>(buffer[i]));
    }
    return false;
  };
  EXPECT_FALSE(read_for(std::chrono::milliseconds(1500))) << "running";
  const auto signalled = Clock::now();
  ::kill(p.pid, SIGTERM);
  // The unit's TimeoutStopSec=5 (firmware/service/epipole.service): systemd kills what is still
  // running then, and the robot's last messages are lost with it.
  const bool hung_up = read_for(std::chrono::milliseconds(5000));
  const double stop_seconds = std::chrono::duration<double>(Clock::now() - signalled).count();
  const auto [code, out] = finish(p);
  std::printf("epipole-fw closed the link %.3f s after SIGTERM\n", stop_seconds);
  EXPECT_TRUE(hung_up) << "the link still open 5 s after SIGTERM: " << out;
  EXPECT_EQ(code, 0) << out;
  EXPECT_NE(out.find("stopped after"), std::string::npos) << out;
  const protocol::DecoderStats& s = decoder.stats();
  EXPECT_GT(s.frames, 10u);
  EXPECT_EQ(s.bad_cobs + s.bad_crc + s.bad_body + s.too_long, 0u) << "no half-sent message";
}

// A datagram socket standing in for systemd's notification socket.
struct NotifySocket {
  std::filesystem::path path;
  int fd = -1;
  explicit NotifySocket(const std::filesystem::path& p) : path(p) {
    fd = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    sockaddr_un a{};
    a.sun_family = AF_UNIX;
    std::strncpy(a.sun_path, p.c_str(), sizeof a.sun_path - 1);
    if (::bind(fd, reinterpret_cast<const sockaddr*>(&a), sizeof a) != 0) {
      throw std::runtime_error("bind");
    }
  }
  ~NotifySocket() { ::close(fd); }
  std::vector<std::string> receive(std::chrono::milliseconds span) {
    std::vector<std::string> out;
    const auto until = Clock::now() + span;
    char buffer[512];
    while (Clock::now() < until) {
      timeval tv{0, 50'000};
      ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
      const ssize_t n = ::recv(fd, buffer, sizeof buffer, 0);
      if (n > 0) out.emplace_back(buffer, static_cast<std::size_t>(n));
    }
    return out;
  }
};

TEST(EpipoleFw, TellsTheServiceManagerItIsReadyAndAlive) {
  BoardFolder board;
  NotifySocket notify(board.rig.dir.path() / "notify");
  const std::string socket_env = "NOTIFY_SOCKET=" + notify.path.string();
  // 400 ms: the board's 100 ms camera timeout may be at most a quarter of the interval.
  const Process p = start({"--board", board.path()}, {socket_env, "WATCHDOG_USEC=400000"});
  const std::vector<std::string> early = notify.receive(std::chrono::milliseconds(1500));
  ::kill(p.pid, SIGTERM);
  const std::vector<std::string> late = notify.receive(std::chrono::milliseconds(1000));
  const auto [code, out] = finish(p);
  EXPECT_EQ(code, 0) << out;
  const auto count = [&](const std::vector<std::string>& v, const std::string& what) {
    return std::count(v.begin(), v.end(), what);
  };
  EXPECT_EQ(count(early, "READY=1"), 1);
  EXPECT_GE(count(early, "WATCHDOG=1"), 3) << "pings at half the 400 ms interval, or faster";
  EXPECT_EQ(count(late, "STOPPING=1"), 1);
}

TEST(EpipoleFw, ACameraTimeoutTheWatchdogCannotWaitForIsAConfigurationError) {
  BoardFolder board;
  NotifySocket notify(board.rig.dir.path() / "notify");
  const Process p = start({"--board", board.path()},
                          {"NOTIFY_SOCKET=" + notify.path.string(), "WATCHDOG_USEC=300000"});
  const auto [code, out] = finish(p);
  EXPECT_EQ(code, 1);
  EXPECT_NE(out.find("cameras.timeout_ms 100 is more than a quarter of the service's watchdog "
                     "interval of 300 ms"),
            std::string::npos)
      << out;
  EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << "one line: " << out;
}

}  // namespace
}  // namespace epipole::firmware
