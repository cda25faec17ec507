#pragma once
// One run of the lockstep co-simulation: the unmodified flight software against the simulated
// Tello (plant + autopilot on CVODE), the Bullet collision world, the EGL camera and the link.
//
// The harness owns time (int64 ns; every event time from integers):
//   autopilot ticks   t = tick(k, autopilot.rate_hz)   plant + autopilot advance, collision
//                                                     swept from the previous pose, truth hashed
//   frame captures    t = tick(f, camera.frame_rate)   after `streamon`: a frame is rendered at the
//                                                     vehicle's pose unless the link drops it,
//                                                     and reaches the flight software after its
//                                                     latency
//   state samples     t = tick(s, cosim.state_rate)    after `command`: the Tello's SDK 2.0 text,
//                                                     parsed by the driver's parser on arrival
//   deliveries        link latencies                   replies and state to the flight software;
//                                                     its commands to the autopilot (after its
//                                                     compute time and the command latency)
// Events at the same instant run in that order (ticks, vehicle-side deliveries, captures,
// samples, flight-software deliveries), ties by their order of scheduling: one run is a pure
// function of (scenario, seed).
//
// A run ends at the first shelf contact, on leaving the arena (a wall, the ceiling, or outside
// the arena box), at a numerical failure of the plant, at an exception of the flight
// software, at its timeout, or when the flight software is done and the vehicle has landed.

#include "render/renderer.hpp"
#include "verification/cosim/run_result.hpp"
#include "verification/scenario/dispersion.hpp"
#include "verification/world/mission_setup.hpp"

namespace shelfcross::verification {

/// Runs one dispersed run. `renderer` must have been made for (or re-targeted at) the run's
/// warehouse and camera; the harness uses it only from the calling thread. Throws
/// std::invalid_argument for a scenario it cannot fly (a start not landed, an unknown
/// strategy); what goes wrong during the run (a contact, a timeout, an exception of the
/// flight software) is the run's outcome, not an exception.
RunResult run_cosimulation(const RunSetup& setup, render::Renderer& renderer,
                           const FrameObserver& observer = {});

}  // namespace shelfcross::verification
