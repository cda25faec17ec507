#pragma once
// Runs the built `shelfcross` program with a subcommand and arguments, as a user would from a
// shell, and returns its exit code with stdout and stderr together.

#include <sys/wait.h>

#include <cstdio>
#include <string>

namespace shelfcross::app::test {

struct ProgramResult {
  int exit_code;
  std::string output;  // stdout and stderr
};

inline ProgramResult run_shelfcross(const std::string& subcommand, const std::string& args) {
  const std::string cmd = std::string(SHELFCROSS_PROGRAM) + " " + subcommand + " " + args + " 2>&1";
  FILE* pipe = popen(cmd.c_str(), "r");
  std::string out;
  char buf[4096];
  while (std::size_t n = std::fread(buf, 1, sizeof buf, pipe)) out.append(buf, n);
  const int status = pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

}  // namespace shelfcross::app::test
