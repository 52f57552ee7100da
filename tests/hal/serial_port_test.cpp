// The termios serial port on real kernel pseudo-terminals: the test holds the master side,
// the port opens the slave device as it would /dev/ttyUSB0.
#include "termios/termios_serial.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <pty.h>
#include <sys/ioctl.h>
#include <termios.h>
#include <unistd.h>

#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include "epipole/core/error.hpp"

namespace epipole::hal {
namespace {

constexpr Nanoseconds kMillisecond = 1'000'000;

class Pty {
 public:
  Pty() {
    int slave = -1;
    std::array<char, 128> name{};
    if (openpty(&master_, &slave, name.data(), nullptr, nullptr) != 0) {
      throw std::runtime_error("openpty failed");
    }
    ::close(slave);  // the port opens it by name
    slave_name_ = name.data();
    fcntl(master_, F_SETFL, fcntl(master_, F_GETFL) | O_NONBLOCK);
  }
  ~Pty() { close_master(); }
  Pty(const Pty&) = delete;
  Pty& operator=(const Pty&) = delete;

  const std::string& slave_name() const { return slave_name_; }
  int master() const { return master_; }
  void close_master() {
    if (master_ >= 0) ::close(master_);
    master_ = -1;
  }
  void send(const std::string& text) const {
    ASSERT_EQ(::write(master_, text.data(), text.size()), static_cast<ssize_t>(text.size()));
  }
  std::string receive(std::size_t count) const {
    std::string out;
    for (int tries = 0; tries < 200 && out.size() < count; ++tries) {
      pollfd p{master_, POLLIN, 0};
      if (::poll(&p, 1, 10) <= 0) continue;
      std::array<char, 4096> buffer{};
      const ssize_t n = ::read(master_, buffer.data(), buffer.size());
      if (n > 0) out.append(buffer.data(), static_cast<std::size_t>(n));
    }
    return out;
  }

 private:
  int master_ = -1;
  std::string slave_name_;
};

std::string read_text(SerialPort& port, std::size_t count) {
  std::string out;
  std::array<std::byte, 256> buffer{};
  for (int tries = 0; tries < 100 && out.size() < count; ++tries) {
    const IoResult r = port.read(buffer, 20 * kMillisecond);
    if (r.status == IoStatus::ok) out.append(reinterpret_cast<const char*>(buffer.data()), r.bytes);
    if (r.status == IoStatus::hung_up) break;
  }
  return out;
}

std::span<const std::byte> bytes_of(const std::string& text) {
  return std::as_bytes(std::span(text.data(), text.size()));
}

class SerialBaud : public ::testing::TestWithParam<int> {};

TEST_P(SerialBaud, BytesGoBothWaysRawAtTheAskedSpeed) {
  if (EPIPOLE_UNDER_QEMU && GetParam() > 460800) {
    GTEST_SKIP() << "qemu-user 7.2 does not translate termios speeds above 460800";
  }
  Pty pty;
  TermiosSerialPort port({pty.slave_name(), GetParam()});
  ASSERT_TRUE(port.is_open());

  termios tty{};
  ASSERT_EQ(tcgetattr(pty.master(), &tty), 0);
  const speed_t expected = GetParam() == 9600     ? B9600
                           : GetParam() == 115200 ? B115200
                           : GetParam() == 230400 ? B230400
                           : GetParam() == 460800 ? B460800
                                                  : B921600;
  EXPECT_EQ(cfgetospeed(&tty), expected);

  // Raw: control characters and bytes above 127 pass untouched, no echo, no line editing.
  const std::string frame("\x00\x01\x7f\x03\n\r\xff\xfe hello", 14);
  pty.send(frame);
  EXPECT_EQ(read_text(port, frame.size()), frame);
  const IoResult w = port.write(bytes_of(frame), 100 * kMillisecond);
  EXPECT_EQ(w.status, IoStatus::ok);
  EXPECT_EQ(w.bytes, frame.size());
  EXPECT_EQ(pty.receive(frame.size()), frame);
}

INSTANTIATE_TEST_SUITE_P(Rates, SerialBaud,
                         ::testing::Values(9600, 115200, 230400, 460800, 921600));

// The firmware takes its port exclusively (TIOCEXCL): nobody else (a getty, ModemManager, a
// second firmware) opens it meanwhile. Read back with TIOCGEXCL on the port's own descriptor.
TEST(SerialPort, TheFirmwareHasItsPortToItself) {
  if (EPIPOLE_UNDER_QEMU) GTEST_SKIP() << "qemu-user 7.2 does not translate TIOCGEXCL";
  Pty pty;
  TermiosSerialPort port({pty.slave_name(), 115200});
  ASSERT_TRUE(port.is_open());
  int exclusive_fds = 0;
  for (const auto& entry : std::filesystem::directory_iterator("/proc/self/fd")) {
    std::error_code ec;
    if (std::filesystem::read_symlink(entry.path(), ec) != pty.slave_name()) continue;
    int exclusive = 0;
    const int fd = std::stoi(entry.path().filename().string());
    if (ioctl(fd, TIOCGEXCL, &exclusive) == 0 && exclusive != 0) ++exclusive_fds;
  }
  EXPECT_EQ(exclusive_fds, 1);
}

TEST(SerialPort, ReadTimesOutWhenNothingComes) {
  Pty pty;
  TermiosSerialPort port({pty.slave_name(), 115200});
  std::array<std::byte, 16> buffer{};
  MonotonicClock clock;
  const Nanoseconds start = clock.now();
  const IoResult r = port.read(buffer, 30 * kMillisecond);
  EXPECT_EQ(r.status, IoStatus::timeout);
  EXPECT_EQ(r.bytes, 0u);
  EXPECT_GE(clock.now() - start, 25 * kMillisecond);
}

TEST(SerialPort, DetectsHangUpAndReportsAFailedReopen) {
  auto pty = std::make_unique<Pty>();
  const std::string device = pty->slave_name();
  TermiosSerialPort port({device, 115200});
  pty->send("before");
  EXPECT_EQ(read_text(port, 6), "before");
  pty->close_master();  // the kernel hangs up the slave side (and drops its unread input)
  std::array<std::byte, 16> buffer{};
  EXPECT_EQ(port.read(buffer, 50 * kMillisecond).status, IoStatus::hung_up);
  EXPECT_EQ(port.write(bytes_of("x"), 10 * kMillisecond).status, IoStatus::hung_up);
  try {
    port.reopen();
    ADD_FAILURE() << "reopened a vanished pty";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(device), std::string::npos) << e.what();
  }
  EXPECT_FALSE(port.is_open());
  EXPECT_EQ(port.read(buffer, 0).status, IoStatus::closed);
  EXPECT_EQ(port.write(bytes_of("x"), 0).status, IoStatus::closed);
}

TEST(SerialPort, ReopensWhileTheDeviceExists) {
  Pty pty;
  TermiosSerialPort port({pty.slave_name(), 57600});
  port.reopen();
  ASSERT_TRUE(port.is_open());
  pty.send("again");
  EXPECT_EQ(read_text(port, 5), "again");
}

TEST(SerialPort, WriteTimesOutWhenTheOtherEndDoesNotRead) {
  Pty pty;
  TermiosSerialPort port({pty.slave_name(), 115200});
  const std::string block(1 << 20, 'x');  // far more than a pty buffers
  const IoResult r = port.write(bytes_of(block), 50 * kMillisecond);
  EXPECT_EQ(r.status, IoStatus::timeout);
  EXPECT_GT(r.bytes, 0u);
  EXPECT_LT(r.bytes, block.size());
}

TEST(SerialPort, BadSettingsNameTheDeviceAndTheSetting) {
  const auto message = [](const SerialConfig& config) {
    try {
      TermiosSerialPort port(config);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message({"/dev/null", 115200}).find("/dev/null"), std::string::npos);  // no tty
  // A device that is not there is waited for (RecoveringSerialPort opens it when it appears).
  EXPECT_EQ(message({"/no/such/tty", 115200}), "no error");
  EXPECT_FALSE(TermiosSerialPort({"/no/such/tty", 115200}).is_open());
  const std::string bad_baud = message({"/dev/ttyS0", 12345});
  EXPECT_NE(bad_baud.find("12345"), std::string::npos) << bad_baud;
  EXPECT_NE(message({"", 115200}).find("no device"), std::string::npos);
  EXPECT_TRUE(is_supported_baud(115200));
  EXPECT_FALSE(is_supported_baud(0));
}

}  // namespace
}  // namespace epipole::hal
