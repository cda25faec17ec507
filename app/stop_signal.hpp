#pragma once
// Ctrl-C and SIGTERM ask a long command (campaign, search, compare, tello-sim) to stop at its
// next safe point (between runs: finished runs are kept and the same command resumes), rather
// than killing it mid-write. One flag per process: a process runs one command.

#include <atomic>

namespace shelfcross::app {

/// The flag SIGINT and SIGTERM set once stop_on_signals() has run.
std::atomic<bool>& stop_requested();
/// SIGINT and SIGTERM set stop_requested() from now on.
void stop_on_signals();
/// SIGINT and SIGTERM end the process at once again (the default action), as under mpirun,
/// whose launcher ends every rank together.
void die_on_signals();

}  // namespace shelfcross::app
