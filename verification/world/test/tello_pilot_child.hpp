#pragma once
// The tello_pilot program as a child process, for the tests that run it
// (tello_pilot_test.cpp; tello_pilot_sheets_test.cpp, its own program as it reads image files):
// started with posix_spawn, its output in files, waited for by a count of short poll() waits,
// never by reading a clock. TELLO_PILOT_PROGRAM is the program's path (CMakeLists.txt).
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "flight_sw/tello/test/loopback.hpp"

extern char** environ;

namespace shelfcross::tello::testing {

namespace fs = std::filesystem;

/// The shipped flight configuration every run of the program here flies with.
inline const std::string kConfig = std::string(SHELFCROSS_SOURCE_DIR) + "/flight_sw/config/paper_test_shelf.yaml";

/// The whole text of a file (the child's output, the flight log).
inline std::string read_file(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

/// An empty folder of its own for one test (the name tells them apart; the pid, parallel runs).
inline fs::path temp_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("tello_pilot_test_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

/// tello_pilot as a child process, its output in files of `dir`; killed if it still runs when
/// this ends.
struct Child {
  pid_t pid = -1;
  fs::path out, err;
  std::optional<int> exit_code;

  Child(const std::vector<std::string>& args, const fs::path& dir) : out(dir / "stdout"), err(dir / "stderr") {
    std::vector<char*> argv;
    std::string program = TELLO_PILOT_PROGRAM;
    argv.push_back(program.data());
    std::vector<std::string> copy = args;
    for (auto& a : copy) argv.push_back(a.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 1, out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_addopen(&fa, 2, err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    EXPECT_EQ(posix_spawn(&pid, program.c_str(), &fa, nullptr, argv.data(), environ), 0);
    posix_spawn_file_actions_destroy(&fa);
  }
  ~Child() {
    if (!exit_code && pid > 0) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, nullptr, 0);
    }
  }
  bool poll_exit() {
    if (exit_code) return true;
    int status = 0;
    if (::waitpid(pid, &status, WNOHANG) == pid) {
      exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      return true;
    }
    return false;
  }
  int wait(int guard_ms = 20000) {
    for (int i = 0; i < guard_ms / 5 && !poll_exit(); ++i) pause_ms(5);
    return exit_code.value_or(-1);
  }
};

/// Runs tello_pilot with `args` to its end: its exit code (-1 if it ran past the guard), its
/// standard error in *err.
inline int run_to_exit(const std::vector<std::string>& args, std::string* err = nullptr) {
  const fs::path dir = temp_dir("usage");
  Child c(args, dir);
  const int code = c.wait();
  if (err) *err = read_file(c.err);
  return code;
}

}  // namespace shelfcross::tello::testing
