// shelfcross diff BASE NEW [--out DIR] [--allow-different-scenarios] [--fail-if-worse ALPHA]:
// two campaigns on the same runs compared pair by pair (verification/report/paired_diff.hpp): identical
// runs, mission success and contacts with the exact McNemar test, every metric's paired
// difference, the flipped runs with their replay commands; diff.md, diff.json and plots.
//
// Exit status: 0 compared (and, with --fail-if-worse, NEW not shown worse); 2 usage error or a
// pairing refused (nothing written); 3 (kExitNewWorse) the gate: NEW worse at ALPHA for mission
// success or contacts (the report is written); 1 any other error.
#include <iomanip>
#include <iostream>
#include <optional>
#include <sstream>

#include "command_registry.hpp"
#include "verification/report/diff_report.hpp"
#include "verification/report/paired_diff.hpp"

namespace shelfcross::app {
namespace {

/// The gate's exit status: distinct from 1 (an error) and 2 (a usage error), so that a script
/// tells "NEW is worse" from "the comparison could not be made".
constexpr int kExitNewWorse = 3;

struct DiffCliOptions {
  std::string base, next;
  std::string out = "out/diff";
  bool allow_different_scenarios = false;
  std::optional<double> fail_if_worse;
  double confidence = 0.95;
};

std::string p_line(const char* what, const verification::EventComparison& e) {
  std::ostringstream s;
  s << std::setprecision(4) << what << ": " << e.table.new_only << " worse in NEW, " << e.table.base_only
    << " better; one-sided p (NEW worse) " << e.mcnemar.p_new_worse << ", two-sided p " << e.mcnemar.p_two_sided;
  return s.str();
}

int run_diff(const DiffCliOptions& o) {
  using namespace verification;
  DiffSide base = load_diff_side(o.base);
  DiffSide next = load_diff_side(o.next);
  PairedDiff diff;
  try {
    diff = pair_campaigns(std::move(base), std::move(next), {o.allow_different_scenarios, o.confidence});
  } catch (const PairingRefused& e) {
    throw UsageError(std::string("cannot pair ") + o.base + " and " + o.next + ": " + e.what() + " (nothing written)");
  }
  DiffReportOptions report;
  report.fail_if_worse_alpha = o.fail_if_worse;
  write_diff_report(diff, o.out, report);
  const std::int64_t base_successes = diff.pairs - diff.failures.table.both - diff.failures.table.base_only;
  const std::int64_t new_successes = diff.pairs - diff.failures.table.both - diff.failures.table.new_only;
  std::cout << diff.pairs << " runs paired (BASE " << diff.base.runs.size() << " of " << diff.base.meta.runs_requested
            << " stored, NEW " << diff.next.runs.size() << " of " << diff.next.meta.runs_requested << ")"
            << (diff.paired_by_seed ? ", by run seed" : "") << "\n"
            << diff.identical << " of " << diff.pairs << " runs identical\n"
            << "mission success: BASE " << base_successes << ", NEW " << new_successes << "\n"
            << p_line("  missions", diff.failures) << "\n"
            << p_line("  contacts", diff.contacts) << "\n"
            << p_line("  near misses", diff.near_misses) << "\n"
            << diff.flips.size() << " runs flipped\n"
            << "wrote " << o.out << "/diff.md, diff.json and plots\n";
  if (o.fail_if_worse && new_is_worse(diff, *o.fail_if_worse)) {
    std::cout << "GATE FAILED: NEW is worse than BASE at " << *o.fail_if_worse << " (exit " << kExitNewWorse << ")\n";
    return kExitNewWorse;
  }
  if (o.fail_if_worse) std::cout << "gate passed: NEW is not shown worse at " << *o.fail_if_worse << "\n";
  return 0;
}

const CommandRegistration kDiff{
    "diff", "Compare two campaigns run by run on the same draws: identical runs, flips, paired tests, a regression gate",
    [](CLI::App& sub) {
      auto o = std::make_shared<DiffCliOptions>();
      sub.add_option("base", o->base, "BASE: a campaign folder (holds results.sqlite) or a results database")
          ->required();
      sub.add_option("new", o->next, "NEW: the same, for the build or setting under test")->required();
      sub.add_option("--out", o->out, "output folder: diff.md, diff.json and plots")->capture_default_str();
      sub.add_flag("--allow-different-scenarios", o->allow_different_scenarios,
                   "pair by run seed even when the scenarios, seeds or draws differ (a link model, a scenario "
                   "switch); the differing keys and draws are listed");
      sub.add_option("--fail-if-worse", o->fail_if_worse,
                     "exit with status 3 when NEW is worse than BASE at this level (one-sided exact McNemar) for "
                     "mission success or contacts")
          ->check(CLI::Range(1e-9, 0.5));
      sub.add_option("--confidence", o->confidence, "confidence of every interval")
          ->capture_default_str()
          ->check(CLI::Range(0.5, 0.9999));
      return [o]() -> int { return run_diff(*o); };
    }};

}  // namespace
}  // namespace shelfcross::app
