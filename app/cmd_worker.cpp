// shelfcross worker --fd N: not for users. A campaign's worker process (verification/
// run_process.hpp): serves runs on the socket N that its parent `shelfcross campaign`,
// `compare` or MPI worker rank opened, until the parent closes it.
#include "command_registry.hpp"
#include "verification/campaign/run_process.hpp"

namespace shelfcross::app {
namespace {

const CommandRegistration kWorker{
    "worker", "",  // hidden: no description (main.cpp)
    [](CLI::App& sub) {
      auto fd = std::make_shared<int>(-1);
      sub.add_option("--fd", *fd, "the socket to the parent")->required()->check(CLI::Range(0, 1 << 20));
      return [fd]() -> int { return verification::serve_worker_runs(*fd); };
    }};

}  // namespace
}  // namespace shelfcross::app
