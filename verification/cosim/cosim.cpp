#include "verification/cosim/cosim.hpp"

#include "verification/cosim/cosim_run.hpp"

namespace shelfcross::verification {

RunResult run_cosimulation(const RunSetup& setup, render::Renderer& renderer, const FrameObserver& observer) {
  RunContext run(setup, renderer, observer);
  return run.cs.link.model == "sdk" ? fly_sdk_link(run) : fly_ideal_link(run);
}

}  // namespace shelfcross::verification
