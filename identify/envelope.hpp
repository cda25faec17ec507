#pragma once
// The identified drone against a scenario, and a scenario centred on it.
//
// Envelope: for each identified parameter the campaign knows (scenario_parameter_names), the
// scenario's draws are the support of its `dispersions:` entry, or its one nominal value when
// it is not dispersed. The 95 % interval of the identification is then
//   inside     wholly within the drawn range (or, not dispersed, it contains the nominal),
//   straddles  partly within (the drone sits at the range's edge: cannot tell),
//   outside    wholly outside (or, not dispersed, it excludes the nominal): the campaign does
//              not fly this drone.
// rc_gain_scale is checked per axis too (each axis's gain over the scenario's nominal of that
// axis): one scale serves all axes in a campaign, so an axis apart from the others is named.
//
// Calibrated scenario: the scenario's autopilot nominals set to the identified gains and time
// constants, and their dispersions replaced by truncated normals centred on them: rc_gain_scale
// mean 1 with the relative standard deviation of the combined gain; each time constant mean
// its estimate; stddev the bootstrap's; truncated at +-3 stddev (inside the parameter's
// allowed range). The senses (senses_fit.hpp) likewise: each identified one against its
// dispersion (or its `senses:` value), and in the calibrated scenario its `senses:` key set and
// its dispersion centred on it; the VPS's noise, an upper bound only, drawn uniformly from 0 to
// the bound (its key: the bound's middle). A sense the scenario neither disperses nor sets (a
// scenario without `senses:` senses exactly) holds only a drone whose interval reaches that
// value. Every other key of the scenario is kept.

#include <optional>
#include <string>
#include <vector>

#include "identify/identification.hpp"
#include "verification/scenario/scenario.hpp"

namespace shelfcross::identify {

/// The scenario's simulated Tello (autopilot and vehicle) as the one identified: its loops'
/// gains and the nominal gains rc_gain_scale multiplies.
IdentifyOptions with_scenario(IdentifyOptions options, const verification::Scenario& scenario);

enum class Verdict { inside, straddles, outside };
const char* verdict_name(Verdict v);

struct EnvelopeEntry {
  std::string parameter;          ///< a dispersion name (rc_gain_scale, ...) or "rc_gain_scale (yaw)"
  Interval identified;            ///< in the scenario parameter's units
  bool dispersed = false;
  double lowest = 0.0, highest = 0.0;  ///< the scenario's draws (nominal: lowest == highest)
  Verdict verdict = Verdict::inside;
};

std::vector<EnvelopeEntry> check_envelope(const Identification& id, const verification::Scenario& scenario);

/// What the scenario draws for each identified parameter that has a scenario counterpart
/// (Identification::parameters names): the gains as their nominal times rc_gain_scale's draws;
/// a parameter not dispersed as its nominal twice.
std::map<std::string, std::pair<double, double>> scenario_ranges(const verification::Scenario& scenario);

/// The scenario with the identified drone as its autopilot (see the file comment).
verification::Scenario calibrated_scenario(const verification::Scenario& scenario, const Identification& id);

/// The overlay alone: the `autopilot:`, `senses:` and `dispersions:` entries calibrated_scenario
/// sets, as YAML to merge by hand into another scenario.
std::string overlay_yaml(const Identification& id);

/// The true values of a drone tello-sim flew: its report's drawn `dispersions` applied to the
/// scenario's nominals, in the names of Identification::parameters. Throws std::runtime_error
/// when the report cannot be read or is not a tello-sim report with numeric dispersions, and
/// std::logic_error for a dispersion with no nominal in the scenario.
std::map<std::string, double> emulator_truth(const std::string& report_json_path, const verification::Scenario& scenario);

}  // namespace shelfcross::identify
