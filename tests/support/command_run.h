// Test helper: runs a command, or the hairrig binary (HAIRRIG_BIN, set by
// tests/CMakeLists.txt), and captures what it prints. Header-only, for tests/.
#pragma once

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>

namespace hairrig_test {

struct CommandRun {
  int exit_code = -1;
  std::string output;  // stdout and stderr
};

// Runs a shell command line; exit_code is -1 when the shell could not be started.
inline CommandRun RunCommand(const std::string& command_line) {
  const std::string cmd = command_line + " 2>&1";
  CommandRun run;
  FILE* pipe = popen(cmd.c_str(), "r");
  if (!pipe) return run;
  std::array<char, 4096> buf;
  size_t n;
  while ((n = fread(buf.data(), 1, buf.size(), pipe)) > 0) run.output.append(buf.data(), n);
  const int status = pclose(pipe);
  run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return run;
}

#ifdef HAIRRIG_BIN
// `env` is prefixed to the command line ("NAME=value ").
inline CommandRun Hairrig(const std::string& args, const std::string& env = "") {
  return RunCommand(env + std::string(HAIRRIG_BIN) + " " + args);
}
#endif

// The JSON summary a command prints last with --json.
inline nlohmann::json LastLineJson(const std::string& output) {
  const size_t end = output.find_last_not_of('\n');
  const size_t start = output.rfind('\n', end);
  return nlohmann::json::parse(output.substr(start == std::string::npos ? 0 : start + 1, end + 1));
}

}  // namespace hairrig_test
