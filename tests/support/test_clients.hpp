#pragma once

// The independent clients the tests check outputs with (tests/clients: Node.js programs on the
// npm packages of tests/clients/package-lock.json, which scripts/setup.sh installs).
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <string>

#include "run_tool.hpp"

namespace epipole::test {

inline std::filesystem::path clients_dir() {
  return std::filesystem::path(source_dir()) / "tests" / "clients";
}

// Whether the clients' packages are installed (else: run scripts/setup.sh).
inline bool clients_installed() {
  return std::filesystem::exists(clients_dir() / "node_modules" / "@mcap" / "core");
}

// `node tests/clients/SCRIPT ARGUMENTS`, its stdout and stderr merged.
inline ToolResult run_client(const std::string& script, const std::string& arguments) {
  const std::string command =
      "node " + (clients_dir() / script).string() + " " + arguments + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) throw std::runtime_error("popen failed");
  return finish_tool(pipe);
}

}  // namespace epipole::test
