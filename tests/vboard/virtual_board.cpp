#include "virtual_board.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <optional>
#include <span>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "test_paths.hpp"

namespace epipole::test {

namespace {

using Clock = std::chrono::steady_clock;

// The board's command with its standard output and error in the console file.
pid_t start_board(const std::vector<std::string>& command, const Environment& environment,
                  const std::string& console_path) {
  std::vector<std::string> words = command;
  std::vector<char*> argv;
  for (std::string& w : words) argv.push_back(w.data());
  argv.push_back(nullptr);

  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error("fork failed");
  if (pid == 0) {
    const int console = open(console_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int null = open("/dev/null", O_RDONLY);
    if (console < 0 || null < 0) _exit(126);
    dup2(null, 0);
    dup2(console, 1);
    dup2(console, 2);
    for (const auto& [name, value] : environment) setenv(name.c_str(), value.c_str(), 1);
    execv(argv[0], argv.data());
    _exit(127);
  }
  return pid;
}

// Connects to QEMU's end of the link; QEMU listens once it has parsed its arguments.
int connect_link(const std::string& path, pid_t qemu, Clock::time_point deadline) {
  while (Clock::now() < deadline) {
    const int fd = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_un address{};
    address.sun_family = AF_UNIX;
    std::snprintf(address.sun_path, sizeof(address.sun_path), "%s", path.c_str());
    if (connect(fd, reinterpret_cast<const sockaddr*>(&address), sizeof(address)) == 0) return fd;
    close(fd);
    if (waitpid(qemu, nullptr, WNOHANG) == qemu) return -1;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return -1;
}

// Reads until QEMU closes the link, the deadline, or (when given) the time to stop.
// What the robot sends back goes out whole before the next read (a few bytes: the socket takes
// them at once).
void answer(int fd, const Robot& robot, protocol::FrameDecoder& decoder,
            std::span<const std::uint8_t> bytes) {
  for (const std::uint8_t b : bytes) {
    const std::optional<protocol::DecodedMessage> m = decoder.push(b);
    if (!m) continue;
    const std::vector<std::uint8_t> reply = robot(*m);
    for (std::size_t done = 0; done < reply.size();) {
      const ssize_t n = write(fd, reply.data() + done, reply.size() - done);
      if (n <= 0) return;
      done += static_cast<std::size_t>(n);
    }
  }
}

void read_until_closed(int fd, std::vector<std::uint8_t>& out, Clock::time_point deadline,
                       Clock::time_point stop = Clock::time_point::max(), const Robot& robot = {}) {
  std::array<std::uint8_t, 4096> buffer{};
  protocol::FrameDecoder decoder;
  while (Clock::now() < deadline && Clock::now() < stop) {
    pollfd p{fd, POLLIN, 0};
    if (poll(&p, 1, 100) <= 0) continue;
    const ssize_t n = read(fd, buffer.data(), buffer.size());
    if (n <= 0) return;
    out.insert(out.end(), buffer.begin(), buffer.begin() + n);
    if (robot) answer(fd, robot, decoder, std::span(buffer.data(), static_cast<std::size_t>(n)));
  }
}

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// The trigger driver's "vboard-trigger: edge N BEFORE AFTER", "vboard-trigger: frame N DONE" and
// "vboard-trigger: pause", and the init's "epipole-fw exit N".
void parse_console(BoardRun& run) {
  std::istringstream in(run.console);
  for (std::string line; std::getline(in, line);) {
    long long number = 0, before = 0, after = 0;
    int code = 0;
    if (const auto at = line.find("vboard-trigger: edge ");
        at != std::string::npos &&
        std::sscanf(line.c_str() + at, "vboard-trigger: edge %lld %lld %lld", &number, &before,
                    &after) == 3) {
      run.edges[number] = TriggerEdge{before, after};
    } else if (const auto frame = line.find("vboard-trigger: frame ");
               frame != std::string::npos &&
               std::sscanf(line.c_str() + frame, "vboard-trigger: frame %lld %lld", &number,
                           &before) == 2) {
      run.frames_done[number] = before;
    } else if (line.find("vboard-trigger: pause") != std::string::npos) {
      run.pauses.push_back(run.edges.empty() ? 0 : run.edges.rbegin()->second.after_ns);
    } else if (const auto exit = line.find("epipole-fw exit ");
               exit != std::string::npos &&
               std::sscanf(line.c_str() + exit, "epipole-fw exit %d", &code) == 1) {
      run.firmware_exit = code;
    }
  }
}

}  // namespace

BoardRun boot_virtual_board(const std::string& arch, const std::string& initramfs,
                            const std::string& kernel_arguments, int timeout_s,
                            double disconnect_after_s, LinkKind link) {
  std::vector<std::string> command = {std::string(source_dir()) + "/scripts/vboard/boot.sh", arch,
                                      initramfs};
  std::istringstream in(kernel_arguments);
  for (std::string w; in >> w;) command.push_back(w);
  return run_board(command, "EPIPOLE_VBOARD_UART",
                   {{"EPIPOLE_VBOARD_LINK", link == LinkKind::usb_serial ? "usb" : "uart"}},
                   "vboard-" + arch, timeout_s, disconnect_after_s);
}

BoardRun run_board(const std::vector<std::string>& command, const std::string& link_variable,
                   Environment environment, const std::string& name, int timeout_s,
                   double disconnect_after_s, const Robot& robot) {
  BoardRun run;
  const std::string base = ::testing::TempDir() + name + "-" + std::to_string(getpid());
  const std::string socket_path = base + ".sock", console_path = base + ".console";
  unlink(socket_path.c_str());
  const auto start = Clock::now();
  const auto deadline = start + std::chrono::seconds(timeout_s);
  environment.emplace_back(link_variable, "socket:" + socket_path);

  const pid_t qemu = start_board(command, environment, console_path);
  if (int fd = connect_link(socket_path, qemu, deadline); fd >= 0) {
    if (disconnect_after_s > 0) {
      while (run.link.empty() && Clock::now() < deadline)
        read_until_closed(fd, run.link, deadline, Clock::now() + std::chrono::milliseconds(100));
      read_until_closed(fd, run.link, deadline,
                        Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                           std::chrono::duration<double>(disconnect_after_s)));
      close(fd);
      run.reconnected_at = run.link.size();
      std::this_thread::sleep_for(std::chrono::seconds(1));
      fd = connect_link(socket_path, qemu, deadline);
    }
    if (fd >= 0) {
      read_until_closed(fd, run.link, deadline, Clock::time_point::max(), robot);
      close(fd);
    }
  }
  int status = 0;
  while (waitpid(qemu, &status, WNOHANG) == 0) {
    if (Clock::now() > deadline) {
      kill(qemu, SIGKILL);
      waitpid(qemu, &status, 0);
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  run.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  unlink(socket_path.c_str());

  run.console = read_file(console_path);
  parse_console(run);
  protocol::FrameDecoder decoder;
  for (const std::uint8_t b : run.link) {
    if (auto m = decoder.push(b)) run.messages.push_back(*m);
  }
  run.decoder = decoder.stats();
  std::ofstream(base + ".link", std::ios::binary)
      .write(reinterpret_cast<const char*>(run.link.data()),
             static_cast<std::streamsize>(run.link.size()));
  return run;
}

}  // namespace epipole::test
