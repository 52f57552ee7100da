#pragma once

// Running the epipole host tool from a test, as a user would from a shell. The program's path
// is test_paths.hpp's tool_path().
#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "test_paths.hpp"

namespace epipole::test {

struct ToolResult {
  int exit_code = -1;
  std::string out;  // stdout, and stderr when it was merged
};

// Starts `epipole ARGUMENTS` with stdout and stderr into the returned pipe.
inline FILE* start_tool(const std::string& arguments) {
  const std::string command = std::string(tool_path()) + " " + arguments + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) throw std::runtime_error("popen failed");
  return pipe;
}

// Reads a started tool's output to the end and waits for it.
inline ToolResult finish_tool(FILE* pipe) {
  ToolResult result;
  std::array<char, 4096> buffer{};
  while (std::fgets(buffer.data(), buffer.size(), pipe) != nullptr) result.out += buffer.data();
  const int status = pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

// Runs `epipole ARGUMENTS` to the end; stderr is merged into the output or discarded.
inline ToolResult run_tool(const std::string& arguments, bool merge_stderr = true) {
  if (merge_stderr) return finish_tool(start_tool(arguments));
  const std::string command = std::string(tool_path()) + " " + arguments + " 2>/dev/null";
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) throw std::runtime_error("popen failed");
  return finish_tool(pipe);
}

inline int line_count(const std::string& text) {
  return static_cast<int>(std::count(text.begin(), text.end(), '\n'));
}

}  // namespace epipole::test
