#pragma once
// The fit report of an identification, written to a folder:
//   identify.md              parameters with 95 % intervals, per-axis fits, the envelope of
//                            the scenario against this drone, the link's figures, the method
//   identify.json            the same, for scripts
//   fit_<axis>.png           measured (state records) against the identified model's response,
//                            with the stick input
//   residuals_<axis>.png     measured minus model
//   overlay.yaml             the autopilot and dispersion entries of the identified drone
//   calibrated_scenario.yaml the scenario (given, else the default) with the overlay applied

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "identify/envelope.hpp"
#include "identify/identification.hpp"
#include "verification/scenario/scenario.hpp"

namespace shelfcross::identify {

struct ReportInputs {
  const Identification* identification = nullptr;
  const verification::Scenario* scenario = nullptr;  ///< for the envelope and the calibrated scenario
  std::string scenario_path;                          ///< as given (for people)
  std::vector<EnvelopeEntry> envelope;
  std::map<std::string, double> truth;                ///< known true values (a tello-sim flight), or none
  std::string truth_source;
};

/// Writes the files above into `dir` (created). Throws std::runtime_error if it cannot.
void write_identify_report(const ReportInputs& in, const std::string& dir);

/// Parameters whose envelope verdict is `outside` (names), for the command's summary.
std::vector<std::string> outside_parameters(const std::vector<EnvelopeEntry>& envelope);

}  // namespace shelfcross::identify
