#pragma once
// One run's setup: the nominal scenario with the run's dispersed parameters (the table in
// dispersion_table.hpp) drawn and applied, and the camera model the flight software believes.

#include <cstdint>
#include <memory>

#include "shelfcross/camera.hpp"
#include "verification/scenario/dispersion_table.hpp"

namespace shelfcross::verification {

struct Scenario;

/// What a run is set up with: the dispersed truth, and the camera model the flight software
/// believes (the truth's intrinsics plus any calibration error).
struct RunSetup {
  std::uint64_t seed = 0;
  DrawnValues drawn;
  std::shared_ptr<const Scenario> scenario;
  CameraIntrinsics believed_camera;
};

/// The nominal scenario with one run's draws applied. Throws std::invalid_argument on draws
/// that do not fit the scenario's dispersions (a value outside its range, a name not dispersed).
RunSetup disperse(const Scenario& nominal, std::uint64_t run_seed);

/// The nominal scenario with the given draws applied instead of the seed's own (a rare-event
/// search draws them from a proposal, rare_event.hpp); the seed still seeds everything else of
/// the run (box placement, noise, the link). `drawn` must hold exactly the scenario's dispersed
/// parameters, each in its allowed range (std::invalid_argument otherwise).
/// disperse(nominal, seed) is disperse(nominal, seed, draw_dispersions(nominal.dispersions, seed)).
RunSetup disperse(const Scenario& nominal, std::uint64_t run_seed, const DrawnValues& drawn);

}  // namespace shelfcross::verification
