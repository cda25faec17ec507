#pragma once
// The campaign report's link section: what the link did in each run (RunMetrics::link, as
// stored) and the success rate against the video datagram loss each run actually met.

#include <filesystem>
#include <string>
#include <vector>

#include "verification/campaign/results_store.hpp"

namespace shelfcross::verification {

/// A markdown section, and link_loss.png in `dir` when any run of the sdk link carried video:
/// runs binned by their measured video datagram loss (lost / sent, 0.5 % bins), each bin's
/// runs, successes, rate and one-sided 95 % Clopper-Pearson lower bound; and the links' models.
/// Requires `dir` to exist. Throws std::invalid_argument when a run's stored metrics do not
/// read (stored_metrics.hpp) and std::runtime_error when the PNG cannot be written.
std::string link_section(const std::vector<RunRecord>& runs, const std::filesystem::path& dir);

}  // namespace shelfcross::verification
