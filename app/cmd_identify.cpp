// shelfcross identify --log FLIGHT.jsonl [--scenario FILE] [--truth REPORT.json] --out DIR:
// the simulated Tello's autopilot parameters identified from a tello_pilot flight log
// (identify/), with their intervals, the fit report, the scenario's envelope against this
// drone and a scenario centred on it (docs/calibration.md).
#include <filesystem>
#include <iostream>
#include <optional>

#include "command_registry.hpp"
#include "identify/envelope.hpp"
#include "identify/flight_record.hpp"
#include "identify/identify_report.hpp"

namespace shelfcross::app {
namespace {

struct IdentifyCliOptions {
  std::string log;
  std::string scenario;
  std::string truth;
  std::string out = "out/identify";
  identify::IdentifyOptions options;
  bool fail_if_outside = false;
};

int run_identify(const IdentifyCliOptions& o) {
  identify::FlightRecord record;
  try {
    record = identify::read_flight_record(o.log);
  } catch (const identify::FlightLogFormatError& e) {
    throw UsageError(std::string("identify: ") + e.what());
  } catch (const std::runtime_error& e) {
    throw UsageError(std::string("identify: ") + e.what());
  }
  // Without --scenario: the default scenario's nominals and envelope.
  const std::string scenario_path = o.scenario.empty() ? verification::kDefaultScenarioFile : o.scenario;
  std::optional<verification::Scenario> scenario;
  if (!o.scenario.empty() || std::filesystem::exists(scenario_path)) scenario = verification::load_scenario(scenario_path);
  const identify::IdentifyOptions options = scenario ? identify::with_scenario(o.options, *scenario) : o.options;
  identify::Identification id;
  try {
    id = identify::identify_flight(record, options);
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("identify: ") + e.what());
  }
  identify::ReportInputs in;
  in.identification = &id;
  if (scenario) {
    in.scenario = &*scenario;
    in.scenario_path = scenario_path;
    in.envelope = identify::check_envelope(id, *scenario);
  }
  if (!o.truth.empty()) {
    if (!scenario) throw UsageError("identify: --truth needs the scenario tello-sim flew (--scenario)");
    in.truth = identify::emulator_truth(o.truth, *scenario);
    in.truth_source = o.truth;
  }
  identify::write_identify_report(in, o.out);
  std::cout << "identify: " << o.log << ", " << id.flight_s << " s of flight\n";
  for (const auto& [name, iv] : id.parameters) {
    std::cout << "  " << name << " = " << iv.value << " [" << iv.lo << ", " << iv.hi << "]";
    if (const auto t = in.truth.find(name); t != in.truth.end()) {
      std::cout << "  true " << t->second << (t->second >= iv.lo && t->second <= iv.hi ? " (within)" : " (NOT within)");
    }
    std::cout << "\n";
  }
  for (const identify::AxisResult& a : id.axes) {
    if (!a.identified) std::cout << "  " << identify::axis_name(a.axis) << " not identified: " << a.why_not << "\n";
  }
  for (const auto& [name, why] : id.senses.not_identified) std::cout << "  " << name << " not identified: " << why << "\n";
  const std::vector<std::string> outside = identify::outside_parameters(in.envelope);
  if (scenario) {
    std::cout << "  against " << scenario_path << ": ";
    if (outside.empty()) std::cout << "no parameter outside its draws\n";
    for (size_t i = 0; i < outside.size(); ++i) std::cout << (i ? ", " : "OUTSIDE its draws: ") << outside[i];
    if (!outside.empty()) std::cout << "\n";
  }
  std::cout << "  report: " << o.out << "/identify.md" << std::endl;
  return o.fail_if_outside && !outside.empty() ? 3 : 0;
}

const CommandRegistration kIdentify{
    "identify", "Identify the Tello's response (autopilot parameters) from a tello_pilot flight log",
    [](CLI::App& sub) {
      auto o = std::make_shared<IdentifyCliOptions>();
      sub.add_option("--log", o->log, "tello_pilot flight log (JSON lines), e.g. from --fly-calibration")->required();
      sub.add_option("--scenario", o->scenario,
                     "scenario whose ranges to check and to centre on this drone (default: the default scenario)");
      sub.add_option("--truth", o->truth, "tello-sim report of the flight: compare with the drone's true values");
      sub.add_option("--out", o->out, "output folder: identify.md, identify.json, plots, overlay.yaml, "
                                      "calibrated_scenario.yaml")->capture_default_str();
      sub.add_option("--bootstrap", o->options.bootstrap_replicates, "bootstrap refits per axis")
          ->capture_default_str()->check(CLI::Range(20, 100000));
      sub.add_option("--seed", o->options.seed, "seed of the bootstrap's resampling")->capture_default_str();
      sub.add_option("--block", o->options.block_s, "bootstrap block length (s)")->capture_default_str()->check(CLI::Range(0.1, 30.0));
      sub.add_option("--board-height", o->options.board_height_m,
                     "height (m) of the board the senses block passed over (tello_pilot --fly-calibration --senses-board): "
                     "identifies how the height hold follows a step of the range reading")
          ->check(CLI::Range(identify::kBoardHeightMin_m, identify::kBoardHeightMax_m));
      sub.add_flag("--fail-if-outside", o->fail_if_outside,
                   "exit 3 when an identified parameter lies outside the scenario's draws");
      return [o]() -> int { return run_identify(*o); };
    }};

}  // namespace
}  // namespace shelfcross::app
