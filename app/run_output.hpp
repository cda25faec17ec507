#pragma once
// Writing one run's outputs (shared by `shelfcross run` and `shelfcross replay`):
//   DIR/run.json         outcome, detail, metrics, hash, seed, drawn dispersions, inventory
//   DIR/trajectory.csv   truth and phase at cosim.trajectory_rate_hz
//   DIR/events.log       phases, commands, replies, contacts, outcome, stamped
//   DIR/video.mp4        (with --video) the camera as the flight software received it, with
//                        its detections drawn on it

#include <filesystem>
#include <memory>

#include "verification/cosim.hpp"

namespace shelfcross::app {

/// Runs `setup` with a renderer of its own and writes the outputs; returns the result.
verification::RunResult run_and_write(const verification::RunSetup& setup, const std::filesystem::path& dir,
                                      bool video);

}  // namespace shelfcross::app
