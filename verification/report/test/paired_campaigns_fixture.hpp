#pragma once
// Small campaigns with known outcomes, written through the real results store: what the paired
// comparison's tests (verification's and the `shelfcross diff` CLI's) read back. Every run has
// its scenario's real draws for its seed and real metrics JSON; only the outcomes, clearances,
// pushes, mission times and run hashes are chosen, so the flips, the tables and the shifts are
// known.

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "shelfcross/random.hpp"
#include "shelfcross/warehouse.hpp"
#include "verification/campaign/campaign.hpp"
#include "verification/campaign/results_store.hpp"
#include "verification/cosim/run_metrics_json.hpp"
#include "verification/scenario/dispersion.hpp"
#include "verification/scenario/scenario.hpp"

namespace shelfcross::verification::test {

/// A run's trajectory through cell (level 2, column 3) of shelf 0 as campaign.cpp stores it
/// (trace_json, 10 Hz): straight along x_S at 0.3 m/s from 1 m before the front face to 1 m
/// past the back face, its body origin `offset_y_m(x_S)` to the left of the cell's centre line.
inline RunResult crossing_trajectory(const Scenario& scenario, const std::function<double(double)>& offset_y_m) {
  const ShelfSpec& shelf = scenario.warehouse.shelves.front();
  const Eigen::Isometry3d X_WS = shelf_pose_W(shelf);
  const Eigen::Vector3d centre_S = cell_centre_S_m(shelf, 2, 3);
  RunResult r;
  for (int k = 0; k * 0.1 * 0.3 <= 2.0 + shelf.depth_m; ++k) {
    const double x_S = -1.0 + k * 0.1 * 0.3;
    TrajectorySample s;
    s.t_s = 10.0 + 0.1 * k;
    s.p_WB_m = X_WS * Eigen::Vector3d(x_S, centre_S.y() + offset_y_m(x_S), centre_S.z());
    s.yaw_rad = shelf.yaw_rad;
    r.trajectory.push_back(s);
  }
  r.approach_start_s = 2.0;
  r.cross_start_s = 10.0 + 0.1 * 30;
  return r;
}

/// What one stored run is made of.
struct PlannedRun {
  std::string outcome = "success";
  double min_clearance_m = 0.10;
  /// The crossing's push (crossing_push.hpp): a success crosses cell (2, 3) of shelf 0 drifting
  /// linearly across the cell from its centre line to this far off it at the back face.
  double push_m = 0.02;
  double mission_time_s = 25.0;
  std::string run_hash;  ///< empty: one made from the seed (the same on both sides)
  /// A draw stored other than the scenario's (as a build that draws differently would).
  std::optional<std::pair<std::string, double>> other_draw;
};

/// The default scenario as a campaign stores it (resolved), with an optional edit of its text.
inline Scenario fixture_scenario(const std::function<void(std::string&)>& edit = {}) {
  Scenario s = load_scenario(std::string(SHELFCROSS_SOURCE_DIR) + "/scenarios/paper_test_shelf.yaml");
  if (!edit) return s;
  std::string yaml = write_scenario(s);
  edit(yaml);
  return parse_scenario(yaml, "edited fixture scenario");
}

/// Writes runs 0..runs-1 of a campaign of `scenario` and `campaign_seed` into `db`, run k as
/// plan(k) says (runs_requested: `requested`, default `runs`).
inline void write_planned_campaign(const std::filesystem::path& db, const Scenario& scenario,
                                   std::uint64_t campaign_seed, std::int64_t runs,
                                   const std::function<PlannedRun(std::int64_t)>& plan,
                                   std::optional<std::int64_t> requested = std::nullopt) {
  std::filesystem::create_directories(db.parent_path());
  ResultsStore store = ResultsStore::open_or_create(
      db, {write_scenario(scenario), campaign_seed, requested.value_or(runs)});
  for (std::int64_t k = 0; k < runs; ++k) {
    const PlannedRun p = plan(k);
    RunRecord r;
    r.index = k;
    r.seed = run_seed(campaign_seed, static_cast<std::uint64_t>(k));
    DrawnValues drawn = draw_dispersions(scenario.dispersions, r.seed);
    if (p.other_draw) drawn[p.other_draw->first] = p.other_draw->second;
    r.dispersion_json = nlohmann::json(drawn).dump();
    r.outcome = p.outcome;
    RunMetrics m;
    m.mission_time_s = p.mission_time_s;
    m.truth.path_length_m = 4.0;
    r.trace_json = "{}";
    if (p.outcome == "success") {
      m.truth.min_clearance_m = p.min_clearance_m;
      m.truth.entry_offset_y_m = 0.0;
      m.truth.entry_offset_z_m = -0.003;
      m.truth.crossed = CellIndex{2, 3};
      const double depth_m = scenario.warehouse.shelves.front().depth_m;
      r.trace_json = trace_json(crossing_trajectory(
          scenario, [&](double x_S) { return p.push_m * std::clamp(x_S / depth_m, 0.0, 1.0); }));
    }
    r.metrics_json = stored_metrics_json({m, p.outcome == "success" ? "" : "planned " + p.outcome, std::nullopt});
    char hash[33];
    std::snprintf(hash, sizeof hash, "%016llx%016llx", static_cast<unsigned long long>(r.seed),
                  static_cast<unsigned long long>(mix64(r.seed)));
    r.run_hash = p.run_hash.empty() ? std::string(hash) : p.run_hash;
    r.wall_s = 1.0;
    r.cpu_s = 2.0;
    store.insert(r);
  }
}

}  // namespace shelfcross::verification::test
