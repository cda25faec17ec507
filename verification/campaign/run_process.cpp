#include "verification/campaign/run_process.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <optional>
#include <stdexcept>
#include <thread>

#include <nlohmann/json.hpp>

#include "verification/campaign/campaign.hpp"
#include "verification/cosim/run_metrics_json.hpp"
#include "verification/scenario/dispersion.hpp"

namespace shelfcross::verification {
namespace {

using nlohmann::json;
// The watchdog's clock: a worker's limits are wall-clock limits by nature.
using Clock = std::chrono::steady_clock;

constexpr int kChildFd = 3;  ///< the socket's number in the child
constexpr double kStartLimit_s = 300.0;  ///< see start_child

Clock::time_point after_s(Clock::time_point t0, double seconds) {
  return t0 + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
}

/// Writes `text` and a newline, whole; false when the peer is gone. MSG_NOSIGNAL: a dead
/// peer is an error to report, not a SIGPIPE that kills the writer.
bool send_line(int fd, const std::string& text) {
  const std::string line = text + "\n";
  size_t sent = 0;
  while (sent < line.size()) {
    const ssize_t n = ::send(fd, line.data() + sent, line.size() - sent, MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    sent += static_cast<size_t>(n);
  }
  return true;
}

enum class Wait { line, closed, timed_out, over_memory };

/// Resident set of process `pid` in MiB; 0 when it cannot be read (the process is gone).
std::int64_t resident_mb(pid_t pid) {
  std::ifstream statm("/proc/" + std::to_string(pid) + "/statm");
  std::int64_t size_pages = 0, resident_pages = 0;
  if (!(statm >> size_pages >> resident_pages)) return 0;
  return resident_pages * static_cast<std::int64_t>(sysconf(_SC_PAGESIZE)) / (1024 * 1024);
}

/// A gap this long between two turns of read_line's loop (which turns at least every 250 ms)
/// means the campaign itself was not running: stopped (Ctrl-Z, SIGSTOP) or the machine
/// suspended. Its workers were stopped with it (they are in its process group), so the gap is
/// not counted against a run's wall-clock limit; a run is `hung` for what it did while the
/// campaign ran. (A campaign stopped for 47 min once recorded its run in flight `hung`
/// on resuming.) A parent merely slow to be scheduled on a loaded machine only delays the
/// verdict.
constexpr auto kNotRunningGap = std::chrono::seconds(5);

/// The next line from `fd` into `line` (`buffer` keeps what follows it). Waits until
/// `deadline` (forever when nullopt), moved later by any time the caller was not running
/// (kNotRunningGap); while waiting, checks that process `watched` (when not 0) stays under
/// `memory_limit_mb` (when > 0).
Wait read_line(int fd, std::string& buffer, std::string& line, std::optional<Clock::time_point> deadline,
               pid_t watched = 0, std::int64_t memory_limit_mb = 0) {
  auto last_turn = Clock::now();
  for (;;) {
    const auto now = Clock::now();
    if (deadline && now - last_turn > kNotRunningGap) *deadline += now - last_turn;
    last_turn = now;
    if (const auto end = buffer.find('\n'); end != std::string::npos) {
      line = buffer.substr(0, end);
      buffer.erase(0, end + 1);
      return Wait::line;
    }
    int timeout_ms = -1;
    if (deadline) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(*deadline - now).count();
      if (left <= 0) return Wait::timed_out;
      timeout_ms = static_cast<int>(std::min<long long>(left, 250));  // the memory check's period
    }
    pollfd p{fd, POLLIN, 0};
    const int ready = ::poll(&p, 1, timeout_ms);
    if (ready < 0 && errno != EINTR) return Wait::closed;
    if (ready > 0) {
      char chunk[65536];
      const ssize_t n = ::read(fd, chunk, sizeof chunk);
      if (n == 0 || (n < 0 && errno != EINTR && errno != EAGAIN)) return Wait::closed;
      if (n > 0) buffer.append(chunk, static_cast<size_t>(n));
    }
    if (watched > 0 && memory_limit_mb > 0 && resident_mb(watched) > memory_limit_mb) return Wait::over_memory;
  }
}

std::string signal_text(int signal_number) {
  const char* abbrev = sigabbrev_np(signal_number);
  return std::to_string(signal_number) + (abbrev ? std::string(" (SIG") + abbrev + ")" : std::string());
}

std::string fixed1(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f", v);
  return text;
}

}  // namespace

double run_wall_limit_s(const Scenario& scenario, const WorkerLimits& limits) {
  return std::max(limits.wall_floor_s, limits.wall_factor * scenario.cosim.timeout_s);
}

ProcessRunWorker::ProcessRunWorker(std::shared_ptr<const Scenario> nominal, WorkerLimits limits, std::string executable,
                                   DrawFunction draw)
    : nominal_(std::move(nominal)),
      draw_(std::move(draw)),
      scenario_yaml_(write_scenario(*nominal_)),
      limits_(limits),
      executable_(std::move(executable)) {
  start_child();
}

ProcessRunWorker::~ProcessRunWorker() {
  if (pid_ > 0) {
    // Closing the socket ends the child's loop; it exits once its renderer is torn down.
    ::close(fd_);
    fd_ = -1;
    int status = 0;
    const auto deadline = Clock::now() + std::chrono::seconds(10);
    while (::waitpid(pid_, &status, WNOHANG) == 0) {
      if (Clock::now() > deadline) {
        ::kill(pid_, SIGKILL);
        ::waitpid(pid_, &status, 0);
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }
}

void ProcessRunWorker::start_child() {
  int sv[2];
  if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sv) != 0) {
    throw std::runtime_error(std::string("worker process: socketpair: ") + std::strerror(errno));
  }
  std::string fd_text = std::to_string(kChildFd);
  std::string subcommand = "worker", fd_option = "--fd";
  char* argv[] = {executable_.data(), subcommand.data(), fd_option.data(), fd_text.data(), nullptr};
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid < 0) {
    ::close(sv[0]);
    ::close(sv[1]);
    throw std::runtime_error(std::string("worker process: fork: ") + std::strerror(errno));
  }
  if (pid == 0) {
    // The child of a multi-threaded process: async-signal-safe calls only, until exec.
    if (sv[1] == kChildFd) {
      ::fcntl(kChildFd, F_SETFD, 0);  // keep it open across exec
    } else if (::dup2(sv[1], kChildFd) < 0) {
      ::_exit(127);
    }
    // Dies with the thread that started it, so no worker outlives its campaign.
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (::getppid() != parent) ::_exit(127);
    // Ctrl-C (to the whole process group) and SIGTERM are the parent's to handle: it lets
    // the runs in flight finish. Ignored dispositions survive exec.
    struct sigaction ignore {};
    ignore.sa_handler = SIG_IGN;
    ::sigaction(SIGINT, &ignore, nullptr);
    ::sigaction(SIGTERM, &ignore, nullptr);
    sigset_t none;
    sigemptyset(&none);
    ::sigprocmask(SIG_SETMASK, &none, nullptr);
    ::execv(argv[0], argv);
    ::_exit(127);
  }
  ::close(sv[1]);
  pid_ = pid;
  fd_ = sv[0];
  buffer_.clear();
  // Start-up (the scenario, the renderer's EGL context and shaders) is not part of a run's
  // limit: it gets the run's limit, but at least kStartLimit_s (a loaded machine).
  const auto deadline = after_s(Clock::now(), std::max(kStartLimit_s, run_wall_limit_s(*nominal_, limits_)));
  std::string line;
  const auto failed = [&](const std::string& why) {
    end_child(true);
    return std::runtime_error("worker process " + executable_ + ": " + why);
  };
  if (!send_line(fd_, json{{"scenario_yaml", scenario_yaml_}}.dump())) throw failed("could not be started");
  switch (read_line(fd_, buffer_, line, deadline, pid_,
                    limits_.memory_limit_mb)) {
    case Wait::line: break;
    case Wait::closed: {
      const int status = end_child(false);
      if (WIFSIGNALED(status)) {
        throw std::runtime_error("worker process killed by signal " + signal_text(WTERMSIG(status)) +
                                 " while starting");
      }
      throw std::runtime_error("worker process " + executable_ + " exited with code " +
                               std::to_string(WEXITSTATUS(status)) + " while starting");
    }
    case Wait::timed_out: throw failed("not ready within its wall-clock limit");
    case Wait::over_memory: throw failed("exceeded the memory limit while starting");
  }
  json reply;
  try {
    reply = json::parse(line);
  } catch (const json::exception&) {
    throw failed("malformed start-up reply");
  }
  if (reply.contains("error")) throw failed(reply["error"].get<std::string>());
  if (!reply.value("ready", false)) throw failed("malformed start-up reply");
}

int ProcessRunWorker::end_child(bool kill_first) {
  if (pid_ <= 0) return 0;
  ::close(fd_);
  fd_ = -1;
  int status = 0;
  if (!kill_first) {
    // Its socket closed: it is exiting (an ASan report or a core dump may take a while);
    // the way it ends is the record's reason, so give it time to end on its own.
    const auto deadline = Clock::now() + std::chrono::seconds(30);
    while (Clock::now() < deadline) {
      const pid_t r = ::waitpid(pid_, &status, WNOHANG);
      if (r == pid_ || (r < 0 && errno != EINTR)) {
        pid_ = 0;
        return status;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }
  ::kill(pid_, SIGKILL);
  while (::waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
  }
  pid_ = 0;
  return status;
}

RunRecord ProcessRunWorker::lost_run_record(std::int64_t index, std::uint64_t seed, const DrawnValues& drawn,
                                            const std::string& outcome, const std::string& detail,
                                            int signal_number) const {
  // No CPU figure (cpu_s none, not 0): the process that ran it is gone, uncounted.
  RunRecord r = worker_error_record(index, seed, detail);
  r.outcome = outcome;
  r.metrics_json =
      stored_metrics_json({std::nullopt, detail, signal_number > 0 ? std::optional<int>(signal_number) : std::nullopt});
  r.dispersion_json = json(drawn).dump();  // for the report and replay
  return r;
}

DrawnValues ProcessRunWorker::draws_of(std::uint64_t seed) const {
  return draw_ ? draw_(seed) : draw_dispersions(nominal_->dispersions, seed);
}

RunRecord ProcessRunWorker::run(std::int64_t index, std::uint64_t seed) {
  if (pid_ <= 0) start_child();  // the previous one died: a fresh worker
  const auto t0 = Clock::now();
  const double limit_s = run_wall_limit_s(*nominal_, limits_);
  // The parent draws (the scenario's own draws or the search round's), so the child has one
  // path, and a lost run's record carries the same draws.
  const DrawnValues drawn = draws_of(seed);
  const json request{{"index", index}, {"seed", seed}, {"draws", drawn}};
  std::string line;
  Wait wait = Wait::closed;
  if (send_line(fd_, request.dump())) {
    wait = read_line(fd_, buffer_, line,
                     after_s(t0, limit_s), pid_,
                     limits_.memory_limit_mb);
  }
  const auto lost = [&](const std::string& outcome, const std::string& detail, int signal_number) {
    RunRecord r = lost_run_record(index, seed, drawn, outcome, detail, signal_number);
    r.wall_s = std::chrono::duration<double>(Clock::now() - t0).count();
    return r;
  };
  switch (wait) {
    case Wait::line: break;
    case Wait::timed_out:
      end_child(true);
      return lost("hung", "no result after " + fixed1(limit_s) + " s of wall-clock time (the limit: max(" +
                              fixed1(limits_.wall_floor_s) + " s, " + fixed1(limits_.wall_factor) + " x cosim.timeout_s " +
                              fixed1(nominal_->cosim.timeout_s) + " s)); worker process killed",
                  0);
    case Wait::over_memory: {
      const std::int64_t used_mb = resident_mb(pid_);
      end_child(true);
      return lost("crashed", "worker process over the memory limit (resident " + std::to_string(used_mb) + " MiB > " +
                                 std::to_string(limits_.memory_limit_mb) + " MiB); killed",
                  0);
    }
    case Wait::closed: {
      const int status = end_child(false);
      if (WIFSIGNALED(status)) {
        return lost("crashed", "worker process killed by signal " + signal_text(WTERMSIG(status)), WTERMSIG(status));
      }
      return lost("crashed", "worker process exited with code " + std::to_string(WEXITSTATUS(status)) + " during the run",
                  0);
    }
  }
  try {
    RunRecord r = decode_run_record(line);
    if (r.index != index || r.seed != seed) throw std::invalid_argument("a record of another run");
    return r;
  } catch (const std::invalid_argument& e) {
    end_child(true);
    return lost("crashed", std::string("worker process sent a malformed record: ") + e.what(), 0);
  }
}

WorkerFactory process_worker_factory(std::shared_ptr<const Scenario> nominal, WorkerLimits limits,
                                     std::string executable, DrawFunction draw) {
  return [nominal, limits, executable, draw](int) {
    return std::make_unique<ProcessRunWorker>(nominal, limits, executable, draw);
  };
}

int serve_worker_runs(int fd) {
  // llvmpipe rasterises on this thread instead of a pool of its own threads (one per CPU by
  // default), unless the user chose otherwise. A campaign already runs one worker per core;
  // the pool only adds hand-overs (`shelfcross run` of the default scenario, ideal link, seed
  // 3, twice each on a loaded machine: 2.0 s of user + system CPU instead of 2.26, the same run
  // hash). And the general protection fault
  // in swrast_dri.so seen in campaigns was, by its address, a race between the context's
  // thread and llvmpipe's rasteriser threads (render/egl_context.cpp): with none, it has
  // nothing to race with. Read when the driver is loaded: before the renderer is made.
  ::setenv("LP_NUM_THREADS", "0", /*overwrite=*/0);
  std::string buffer, line;
  if (read_line(fd, buffer, line, std::nullopt) != Wait::line) return 1;
  std::unique_ptr<CampaignWorker> worker;
  try {
    const json setup = json::parse(line);
    auto nominal = std::make_shared<const Scenario>(
        parse_scenario(setup.at("scenario_yaml").get<std::string>(), "the campaign's scenario"));
    worker = std::make_unique<CampaignWorker>(nominal, DrawFunction{}, CpuClock::process);
  } catch (const std::exception& e) {
    send_line(fd, json{{"error", e.what()}}.dump());
    return 1;
  }
  if (!send_line(fd, json{{"ready", true}}.dump())) return 1;
  while (read_line(fd, buffer, line, std::nullopt) == Wait::line) {
    std::int64_t index = 0;
    std::uint64_t seed = 0;
    DrawnValues draws;
    try {
      const json request = json::parse(line);
      index = request.at("index").get<std::int64_t>();
      seed = request.at("seed").get<std::uint64_t>();
      draws = request.at("draws").get<DrawnValues>();
    } catch (const json::exception&) {
      return 1;  // the parent records the run as crashed: it cannot be a run of this campaign
    }
    RunRecord record;
    try {
      record = worker->run_drawn(index, seed, draws);
    } catch (const std::exception& e) {
      record = worker_error_record(index, seed, e.what());  // no CPU figure, as in a worker thread
    }
    if (!send_line(fd, encode_run_record(record))) return 1;
  }
  return 0;
}

}  // namespace shelfcross::verification
