// epipole view BOARD_OR_HOST: where a board's live view is (docs/live-view.md), whether it
// answers, and with --open the page in this desk's browser.
//
//   epipole view board/sim           the view of a board file (its outputs.view), on this machine
//   epipole view 192.168.1.20[:8765] the view of a board on the network
#include <civetweb.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <array>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <string>

#include "commands.hpp"
#include "epipole/core/error.hpp"
#include "epipole/firmware/board_config.hpp"

namespace epipole::tools {

namespace {

namespace fs = std::filesystem;

constexpr int kDefaultPort = 8765;

struct ViewOptions {
  std::string target;
  bool open = false;
  double timeout_s = 2;
};

struct Address {
  std::string host;
  int port = kDefaultPort;
};

// A board file's view: its outputs.view's port, on this machine (its bind address when that is
// one interface's).
Address board_view(const fs::path& board) {
  const firmware::BoardConfig config = firmware::load_board_config(board);  // checks it whole
  require(config.outputs.find("view") != nullptr, board.string(),
          ": the board has no live view (outputs: {view: {port: 8765}} turns it on)");
  const fs::path file = fs::is_directory(board) ? board / "board.yaml" : board;
  const YAML::Node view = YAML::LoadFile(file.string())["outputs"]["view"];
  Address a{"127.0.0.1", kDefaultPort};
  if (view.IsMap() && view["port"]) a.port = view["port"].as<int>();
  require(a.port != 0, board.string(),
          ": outputs.view.port is 0: the system picks the port, and the firmware's journal says "
          "which (epipole view HOST:PORT)");
  if (view.IsMap() && view["bind"]) {
    const std::string bind = view["bind"].as<std::string>();
    if (bind != "0.0.0.0") a.host = bind;
  }
  return a;
}

// HOST, HOST:PORT, [IPv6] or [IPv6]:PORT.
Address host_view(const std::string& target) {
  Address a{target, kDefaultPort};
  const std::size_t bracket = target.rfind(']');
  if (target.starts_with('[') && bracket != std::string::npos)
    a.host = target.substr(1, bracket - 1);
  const std::size_t colon = target.rfind(':');
  const bool has_port =
      colon != std::string::npos &&
      (bracket != std::string::npos ? colon == bracket + 1 : target.find(':') == colon);
  if (has_port) {
    if (bracket == std::string::npos) a.host = target.substr(0, colon);
    const std::string port = target.substr(colon + 1);
    char* end = nullptr;
    const long value = std::strtol(port.c_str(), &end, 10);
    require(!port.empty() && *end == '\0' && value > 0 && value < 65536, "view ", target, ": '",
            port, "' is not a port");
    a.port = static_cast<int>(value);
  }
  require(!a.host.empty(), "view ", target, ": no host");
  return a;
}

// GET /api/health: the health the board sends, or an error saying why there is none.
nlohmann::json board_health(const Address& a, double timeout_s) {
  std::array<char, 256> error{};
  mg_connection* conn = mg_connect_client(a.host.c_str(), a.port, 0, error.data(), error.size());
  require(conn != nullptr, "nothing answers at ", a.host, ":", a.port, " (", error.data(),
          "): is epipole-fw running there with outputs.view on?");
  mg_printf(conn, "GET /api/health HTTP/1.0\r\nHost: %s\r\n\r\n", a.host.c_str());
  const int got =
      mg_get_response(conn, error.data(), error.size(), static_cast<int>(timeout_s * 1000));
  const mg_response_info* response = got >= 0 ? mg_get_response_info(conn) : nullptr;
  std::string body;
  std::array<char, 4096> buffer{};
  for (int n; response != nullptr && (n = mg_read(conn, buffer.data(), buffer.size())) > 0;) {
    body.append(buffer.data(), static_cast<std::size_t>(n));
  }
  const int status = response != nullptr ? response->status_code : 0;
  mg_close_connection(conn);
  require(status == 200, a.host, ":", a.port, " answered ",
          status == 0 ? cat("nothing (", error.data(), ")") : cat("HTTP ", status),
          " for its health: not an Epipole live view, or not ready yet");
  const nlohmann::json health = nlohmann::json::parse(body, nullptr, false);
  require(health.is_object(), a.host, ":", a.port, ": its health is not JSON");
  return health;
}

void run_view(const ViewOptions& options) {
  std::error_code ec;
  const bool board =
      fs::exists(options.target, ec) &&
      (fs::is_directory(options.target) || fs::path(options.target).extension() == ".yaml");
  const Address a = board ? board_view(options.target) : host_view(options.target);
  const std::string host = a.host.find(':') != std::string::npos ? "[" + a.host + "]" : a.host;
  const std::string page = cat("http://", host, ":", a.port, "/");
  std::cout << "view: the page: " << page << "\n"
            << "view: Foxglove or Lichtblick: Open connection, Foxglove WebSocket, ws://" << host
            << ":" << a.port << "\n";
  mg_init_library(0);
  const nlohmann::json health = board_health(a, options.timeout_s);
  std::cout << "view: it answers: " << health.value("frames", 0) << " pairs, "
            << health.value("fps_centi", 0) / 100.0 << " pairs a second, up "
            << health.value("uptime_ms", 0) / 1000 << " s\n";
  if (options.open) {
    const char* argv[] = {"xdg-open", page.c_str(), nullptr};
    pid_t pid = 0;
    int status = -1;
    const bool opened = ::posix_spawnp(&pid, "xdg-open", nullptr, nullptr,
                                       const_cast<char* const*>(argv), environ) == 0 &&
                        ::waitpid(pid, &status, 0) == pid && WIFEXITED(status) &&
                        WEXITSTATUS(status) == 0;
    require(opened, "view: xdg-open could not open ", page,
            " (no desktop here? open it in a browser)");
  }
}

}  // namespace

void add_view_command(CLI::App& app, const GlobalOptions&) {
  auto options = std::make_shared<ViewOptions>();
  CLI::App* cmd = app.add_subcommand(
      "view", "Where a board's live view is (a board file's, or a host's), and whether it answers");
  cmd->add_option("target", options->target,
                  "A board folder or file (its outputs.view), or HOST[:PORT] (default port 8765)")
      ->required();
  cmd->add_flag("--open", options->open, "Open the page in this desk's browser (xdg-open)");
  cmd->add_option("--timeout", options->timeout_s, "Seconds to wait for the board's answer")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->callback([options] { run_view(*options); });
}

}  // namespace epipole::tools
