// epipole link PORT: decodes Epipole's serial stream for people, and sends commands.
#include <sys/stat.h>

#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <vector>

#include "commands.hpp"
#include "epipole/core/error.hpp"
#include "epipole/firmware/protocol/codec.hpp"
#include "epipole/firmware/protocol/fields.hpp"
#include "epipole/hal/registry.hpp"
#include "epipole/hal/serial_port.hpp"
#include "message_json.hpp"

namespace epipole::tools {

namespace {

using namespace epipole::protocol;

struct LinkOptions {
  std::string port;
  std::string protocol = "epipole";  // or mavlink: the board's serial.protocol
  int baud = 115200;
  bool json = false;
  int count = 0;         // stop after this many messages (0: no limit)
  double seconds = 0.0;  // stop after this long (0: until the stream ends)
  std::vector<std::string> send;
  std::string trajectory;  // the poses decoded, as a TUM trajectory file
};

// The odometry's poses as they are decoded, one TUM line each (timestamp tx ty tz qx qy qz qw):
// the native message's tracked pairs (the rectified left camera in the odometry frame, at its
// trigger time), or MAVLink ODOMETRY's (the body in LOCAL_FRD, at time_usec), lost ones left out.
class TrajectoryWriter {
 public:
  explicit TrajectoryWriter(const std::string& file) : out_(file) {
    require(out_.good(), file, ": cannot write the trajectory");
  }
  void add(const nlohmann::json& m) {
    if (m["type"] != "odometry") return;
    if (m.contains("status")) {  // native
      if (m["status"].get<int>() != static_cast<int>(OdometryStatus::tracking)) return;
      line(static_cast<double>(m["trigger_ns"].get<std::uint64_t>()) / 1e9,
           {m["x_mm"].get<double>() / 1000, m["y_mm"].get<double>() / 1000,
            m["z_mm"].get<double>() / 1000},
           {m["qx_e9"].get<double>() * 1e-9, m["qy_e9"].get<double>() * 1e-9,
            m["qz_e9"].get<double>() * 1e-9, m["qw_e9"].get<double>() * 1e-9});
      return;
    }
    if (m["quality"].get<int>() < 0) return;  // MAVLink: lost
    const nlohmann::json& q = m["q"];         // w, x, y, z
    line(static_cast<double>(m["time_usec"].get<std::uint64_t>()) / 1e6,
         {m["x"].get<double>(), m["y"].get<double>(), m["z"].get<double>()},
         {q[1].get<double>(), q[2].get<double>(), q[3].get<double>(), q[0].get<double>()});
  }

 private:
  void line(double time, std::array<double, 3> t, std::array<double, 4> q) {
    char text[256];
    std::snprintf(text, sizeof text, "%.9f %.6f %.6f %.6f %.9f %.9f %.9f %.9f\n", time, t[0], t[1],
                  t[2], q[0], q[1], q[2], q[3]);
    out_ << text;
    out_.flush();
  }
  std::ofstream out_;
};

std::string to_text(const nlohmann::json& json) {
  std::string line = cat("#", json["seq"].dump(), " ", json["type"].get<std::string>());
  for (const auto& [key, value] : json.items()) {
    if (key == "seq" || key == "type") continue;
    line += cat(" ", key, "=", value.dump());
  }
  return line;
}

// "trigger-rate=30", "exposure=5000" or "exposure=5000:6.5" (µs, dB), "stages=0x3f",
// "snapshot".
Message parse_command(const std::string& text) {
  const auto equals = text.find('=');
  const std::string name = text.substr(0, equals);
  const std::string value = equals == std::string::npos ? "" : text.substr(equals + 1);
  const auto number = [&text](const std::string& s) {
    std::size_t used = 0;
    double v = 0;
    try {
      v = std::stod(s, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    require(used == s.size() && !s.empty() && std::isfinite(v) && v >= 0, "command '", text, "': '",
            s, "' is not a number >= 0");
    return v;
  };
  if (name == "snapshot" && value.empty()) return Snapshot{};
  if (name == "recalibrate" && value.empty()) return Recalibrate{};
  if (name == "save-calibration" && value.empty()) return SaveCalibration{};
  if (name == "record" && value == "stop") return Record{RecordAction::stop, 0};
  if (name == "record" && value.starts_with("start")) {
    const std::string seconds = value == "start" ? "0" : value.substr(value.find(':') + 1);
    require(value == "start" || value.starts_with("start:"), "command '", text,
            "': record=start, record=start:SECONDS or record=stop");
    const double s = number(seconds);
    require(s <= 65535, "command '", text, "': at most 65535 s");
    return Record{RecordAction::start, static_cast<std::uint16_t>(std::lround(s))};
  }
  if (name == "trigger-rate") {
    const double hz = number(value);
    require(hz <= 1000, "command '", text, "': trigger rate above 1000 Hz");
    return SetTriggerRate{static_cast<std::uint32_t>(std::lround(hz * 1000))};
  }
  if (name == "exposure") {
    const auto colon = value.find(':');
    const double exposure = number(value.substr(0, colon));
    const double gain = colon == std::string::npos ? 0.0 : number(value.substr(colon + 1));
    require(exposure <= 1e7 && gain <= 600, "command '", text, "': exposure or gain out of range");
    return SetExposure{static_cast<std::uint32_t>(std::lround(exposure)),
                       static_cast<std::uint16_t>(std::lround(gain * 100))};
  }
  if (name == "stages") {
    std::size_t used = 0;
    unsigned long mask = 0;
    try {
      mask = std::stoul(value, &used, 0);
    } catch (const std::exception&) {
      used = 0;
    }
    require(used == value.size() && !value.empty() && mask <= 0xFFFF, "command '", text,
            "': the stage mask must be a number from 0 to 0xffff");
    return SetStages{static_cast<std::uint16_t>(mask)};
  }
  throw Error(cat("unknown command '", text,
                  "' (expected trigger-rate=HZ, exposure=US[:DB], stages=MASK, snapshot, "
                  "record=start[:SECONDS], record=stop, recalibrate or save-calibration)"));
}

class Printer {
 public:
  explicit Printer(const LinkOptions& options)
      : options_(options),
        decoder_(options.protocol == "mavlink" ? JsonStreamDecoder::Protocol::mavlink
                                               : JsonStreamDecoder::Protocol::epipole) {
    if (!options.trajectory.empty()) trajectory_.emplace(options.trajectory);
  }
  // Feeds bytes; false once enough messages were printed.
  bool feed(std::span<const std::uint8_t> bytes) {
    const bool more =
        decoder_.feed(bytes, [this](const nlohmann::json& json) { return print(json); });
    std::cout.flush();
    return more;
  }
  void finish() {
    if (!enough()) decoder_.finish([this](const nlohmann::json& json) { return print(json); });
    const nlohmann::json stats = decoder_.stats();
    if (options_.json) {
      std::cout << stats.dump() << "\n";
    } else {
      std::cerr << "epipole link: " << stats.dump() << "\n";
    }
  }

 private:
  // False once enough messages were printed.
  bool print(const nlohmann::json& json) {
    if (trajectory_) trajectory_->add(json);
    std::cout << (options_.json ? json.dump() : to_text(json)) << "\n";
    ++printed_;
    return !enough();
  }
  bool enough() const { return options_.count > 0 && printed_ >= options_.count; }

  const LinkOptions& options_;
  JsonStreamDecoder decoder_;
  std::optional<TrajectoryWriter> trajectory_;
  int printed_ = 0;
};

bool is_terminal(const std::string& path) {
  struct stat info {};
  return ::stat(path.c_str(), &info) == 0 && S_ISCHR(info.st_mode);
}

void run_link(const LinkOptions& options) {
  std::vector<Message> commands;
  for (const std::string& text : options.send) commands.push_back(parse_command(text));
  require(commands.empty() || options.protocol == "epipole",
          "--send: a board speaking MAVLink reads no commands");
  Printer printer(options);

  if (!is_terminal(options.port)) {
    require(commands.empty(), options.port, ": commands can only be sent to a serial device");
    std::ifstream in(options.port, std::ios::binary);
    require(in.good(), options.port, ": cannot open");
    std::array<char, 4096> buffer{};
    while (in.read(buffer.data(), buffer.size()) || in.gcount() > 0) {
      const auto n = static_cast<std::size_t>(in.gcount());
      if (!printer.feed(std::span(reinterpret_cast<const std::uint8_t*>(buffer.data()), n))) break;
    }
    printer.finish();
    return;
  }

  const std::unique_ptr<hal::SerialPort> opened =
      hal::BackendRegistry::builtin().create_serial("termios", {options.port, options.baud});
  hal::SerialPort& port = *opened;
  std::array<std::uint8_t, kMaxFrameSize> frame{};
  std::uint16_t sequence = 0;
  for (const Message& command : commands) {
    const std::size_t size = encode_frame(command, sequence++, frame);
    const hal::IoResult sent =
        port.write(std::as_bytes(std::span(frame.data(), size)), 1'000'000'000);
    require(sent.status == hal::IoStatus::ok, options.port, ": could not send '",
            name_of(type_of(command)), "'");
  }
  const auto start = std::chrono::steady_clock::now();
  std::array<std::byte, 4096> buffer{};
  for (;;) {
    const double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (options.seconds > 0 && elapsed >= options.seconds) break;
    const hal::IoResult r = port.read(buffer, 100'000'000);
    if (r.status == hal::IoStatus::hung_up) {
      std::cerr << "epipole link: " << options.port << " hung up\n";
      break;
    }
    if (r.status != hal::IoStatus::ok) continue;
    if (!printer.feed(std::span(reinterpret_cast<const std::uint8_t*>(buffer.data()), r.bytes))) {
      break;
    }
  }
  printer.finish();
}

}  // namespace

void add_link_command(CLI::App& app, const GlobalOptions&) {
  auto options = std::make_shared<LinkOptions>();
  CLI::App* cmd = app.add_subcommand(
      "link",
      "Decode Epipole's serial stream (a serial device or a recorded file) and send commands");
  cmd->add_option("port", options->port,
                  "Serial device (e.g. /dev/ttyUSB0) or a recorded stream file")
      ->required();
  cmd->add_option("--protocol", options->protocol,
                  "The board's serial.protocol: epipole, or mavlink")
      ->check(CLI::IsMember({"epipole", "mavlink"}))
      ->capture_default_str();
  cmd->add_option("--baud,-b", options->baud, "Baud rate of a serial device")
      ->check([](const std::string& v) {
        try {
          return hal::is_supported_baud(std::stoi(v)) ? std::string() : "unsupported baud rate";
        } catch (const std::exception&) {
          return std::string("not a number");
        }
      })
      ->capture_default_str();
  cmd->add_flag("--json", options->json, "One JSON object per message, then the decoder's counts");
  cmd->add_option("--trajectory", options->trajectory,
                  "Write the odometry's tracked poses to FILE as a TUM trajectory (timestamp tx ty "
                  "tz qx qy qz qw), for evo and other trajectory tools");
  cmd->add_option("--count,-n", options->count, "Stop after N messages")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--seconds,-s", options->seconds, "Stop after this long (serial devices)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--send", options->send,
                  "Send a command first: trigger-rate=HZ, exposure=US[:DB], stages=MASK, snapshot, "
                  "record=start[:SECONDS], record=stop, recalibrate, save-calibration");
  cmd->callback([options] { run_link(*options); });
}

}  // namespace epipole::tools
