#include "verification/search/search_report.hpp"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>

#include "verification/campaign/results_store.hpp"
#include "verification/plot/plot.hpp"
#include "verification/search/search.hpp"
#include "verification/statistics/statistics.hpp"

namespace shelfcross::verification {
namespace {

const cv::Scalar kNominalRound(150, 150, 150), kAdaptRound(200, 120, 40), kEstimateRound(60, 160, 60),
    kFailure(40, 40, 220);

std::string fmt(double v, const char* format = "%.4g") {
  if (std::isnan(v)) return "-";
  char text[64];
  std::snprintf(text, sizeof text, format, v);
  return text;
}

nlohmann::json number_or_null(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

std::string describe(const Distribution& d) {
  switch (d.kind) {
    case Distribution::Kind::uniform: return "uniform [" + fmt(d.min) + ", " + fmt(d.max) + "]";
    case Distribution::Kind::normal: return "normal " + fmt(d.mean) + " +- " + fmt(d.stddev);
    case Distribution::Kind::truncated_normal:
      return "normal " + fmt(d.mean) + " +- " + fmt(d.stddev) + " on [" + fmt(d.min) + ", " + fmt(d.max) + "]";
    case Distribution::Kind::choice: {
      std::string s = "choice";
      double total = 0.0;
      for (double w : d.weights) total += w;
      for (size_t i = 0; i < d.values.size(); ++i) {
        s += ' ';
        s += fmt(d.values[i]);
        s += ':';
        s += fmt(d.weights[i] / total, "%.2f");
      }
      return s;
    }
  }
  return "?";
}

/// One stored run as the report sees it.
struct Row {
  const RunRecord* record = nullptr;
  int round = -1;
  DrawnValues drawn;
  RunMargins margins;
  double log_nominal = 0.0;   ///< log f(x)
  double log_proposal = 0.0;  ///< log q_round(x)
};

struct ClassEstimate {
  IsEstimate is;
  int round = -1;  ///< the round whose runs it uses
  IsEstimate every_round;  ///< from every stored run, weighted by mixture_log_weight
  /// Upper 95 % bounds on p from the same runs, used when none failed (zero_failure_upper_bound),
  /// and those runs' worth in nominal runs (nominal_worth).
  double bound_round = 1.0, bound_every_round = 1.0;
  double worth_round = 0.0, worth_every_round = 0.0;
};

nlohmann::json estimate_json(const IsEstimate& e) {
  return {{"runs", e.runs}, {"failures", e.failures}, {"p_hat", e.p_hat},
          {"standard_error", number_or_null(e.standard_error)}, {"confidence", e.confidence},
          {"lower", e.lower}, {"upper", e.upper}, {"clt_lower", e.clt_lower}, {"clt_upper", e.clt_upper},
          {"failure_ess", e.failure_ess}, {"mean_weight", e.mean_weight}, {"doubts", estimate_doubts(e)}};
}

/// Plain Monte Carlo over a campaign of the same scenario: its failures of a class over its runs.
struct PlainEstimate {
  std::int64_t runs = 0, failures = 0, first_failure = -1;
  double lower = 0.0, upper = 0.0;  ///< two-sided 95 % Clopper-Pearson
};

/// Everything the report says, computed once from the stores. Rows point into `records`.
struct SearchAnalysis {
  Scenario nominal;
  ParameterDistributions f;  ///< the nominal dispersions
  nlohmann::json settings;
  FailureClass target = FailureClass::contact;
  std::string margin_label;
  std::vector<CeRound> rounds;
  std::vector<RunRecord> records;
  std::vector<Row> rows;  ///< the stored runs of the stored rounds
  int estimate_round = -1;
  std::map<FailureClass, ClassEstimate> estimates;
  std::map<FailureClass, PlainEstimate> plain;  ///< empty without a campaign
  std::vector<const Row*> failures;             ///< of the target class, in run order
  const Row* most_likely = nullptr;             ///< the failure of highest nominal density
};

/// Each stored run of a stored round with its draws, margins and log densities (NaN for a
/// worker_error run, which draws nothing usable).
std::vector<Row> read_rows(const SearchAnalysis& a) {
  using nlohmann::json;
  std::vector<Row> rows;
  for (const RunRecord& r : a.records) {
    Row row;
    row.record = &r;
    for (const CeRound& round : a.rounds) {
      if (r.index >= round.first_run && r.index < round.first_run + round.runs) row.round = round.index;
    }
    if (row.round < 0) continue;  // not a run of a stored round
    row.drawn = json::parse(r.dispersion_json).get<DrawnValues>();
    row.margins = record_margins(a.nominal, r);
    if (r.outcome == "worker_error") {
      row.log_nominal = row.log_proposal = std::numeric_limits<double>::quiet_NaN();
    } else {
      row.log_nominal = log_density(a.f, row.drawn);
      row.log_proposal = a.rounds[static_cast<size_t>(row.round)].proposal.log_pdf(row.drawn);
    }
    rows.push_back(std::move(row));
  }
  return rows;
}

/// Per class, the importance-sampling estimate from the estimation round (or the last round
/// while adaptation goes on) and from every stored run, with the zero-failure bounds.
std::map<FailureClass, ClassEstimate> class_estimates(const SearchAnalysis& a) {
  std::map<FailureClass, ClassEstimate> estimates;
  for (FailureClass c : kFailureClasses) {
    std::vector<double> log_w;
    std::vector<bool> failed;
    for (const Row& row : a.rows) {
      if (row.round != a.estimate_round || std::isnan(row.log_nominal)) continue;
      log_w.push_back(row.log_nominal - row.log_proposal);
      failed.push_back(row.margins.failed(c));
    }
    estimates[c] = {importance_estimate(log_w, failed), a.estimate_round, {}};
  }
  // And from every stored run: each round's proposal in the mixture by its stored run count.
  std::vector<std::int64_t> stored_per_round(a.rounds.size(), 0);
  for (const Row& row : a.rows) {
    if (!std::isnan(row.log_nominal)) ++stored_per_round[static_cast<size_t>(row.round)];
  }
  std::vector<double> mixture_log_w;
  for (const Row& row : a.rows) {
    if (!std::isnan(row.log_nominal)) mixture_log_w.push_back(mixture_log_weight(a.f, a.rounds, stored_per_round, row.drawn));
  }
  // The zero-failure bounds and the worth in nominal runs: the estimation round alone, and
  // every round.
  std::vector<CeRound> last_round;
  std::vector<std::int64_t> last_stored;
  if (a.estimate_round >= 0) {
    last_round.push_back(a.rounds[static_cast<size_t>(a.estimate_round)]);
    last_stored.push_back(stored_per_round[static_cast<size_t>(a.estimate_round)]);
  }
  const double bound_every_round = zero_failure_upper_bound(a.rounds, stored_per_round);
  const double bound_round = zero_failure_upper_bound(last_round, last_stored);
  const double worth_every_round = nominal_worth(a.rounds, stored_per_round);
  const double worth_round = nominal_worth(last_round, last_stored);
  for (FailureClass c : kFailureClasses) {
    std::vector<bool> failed;
    for (const Row& row : a.rows) {
      if (!std::isnan(row.log_nominal)) failed.push_back(row.margins.failed(c));
    }
    estimates[c].every_round = importance_estimate(mixture_log_w, failed);
    estimates[c].bound_round = bound_round;
    estimates[c].bound_every_round = bound_every_round;
    estimates[c].worth_round = worth_round;
    estimates[c].worth_every_round = worth_every_round;
  }
  return estimates;
}

/// Plain Monte Carlo from the campaign in `campaign_dir`; refused (ResultsMismatch) when it
/// holds another scenario than the search's.
std::map<FailureClass, PlainEstimate> plain_estimates(const SearchAnalysis& a, const std::string& scenario_yaml,
                                                      const std::filesystem::path& campaign_dir) {
  std::map<FailureClass, PlainEstimate> plain;
  const ResultsStore campaign = ResultsStore::open_existing(campaign_dir / "results.sqlite");
  if (campaign.meta().scenario_yaml != scenario_yaml) {
    throw ResultsMismatch((campaign_dir / "results.sqlite").string() +
                          " holds a campaign of another scenario than the search's");
  }
  for (const RunRecord& r : campaign.runs()) {
    if (r.outcome == "worker_error") continue;
    const RunMargins m = record_margins(a.nominal, r);
    for (FailureClass c : kFailureClasses) {
      PlainEstimate& p = plain[c];
      ++p.runs;
      if (m.failed(c)) {
        ++p.failures;
        if (p.first_failure < 0) p.first_failure = r.index;
      }
    }
  }
  for (auto& [c, p] : plain) {
    // Two-sided 95 %: each one-sided bound at 97.5 %.
    p.lower = p.failures > 0 ? clopper_pearson_lower(p.failures, p.runs, 0.975) : 0.0;
    p.upper = clopper_pearson_upper(p.failures, p.runs, 0.975);
  }
  return plain;
}

void write_margins_csv(const std::filesystem::path& dir, const SearchAnalysis& a) {
  std::ofstream csv(dir / "margins.csv");
  csv << "run,round,outcome,contact_m,crossing_m,mission,log_nominal_density,log_proposal_density";
  for (const auto& [name, d] : a.f) csv << "," << name;
  csv << "\n";
  for (const Row& row : a.rows) {
    csv << row.record->index << "," << row.round << "," << row.record->outcome << "," << fmt(row.margins.contact_m, "%.6g")
        << "," << fmt(row.margins.crossing_m, "%.6g") << "," << fmt(row.margins.mission, "%.6g") << ","
        << fmt(row.log_nominal, "%.6g") << "," << fmt(row.log_proposal, "%.6g");
    for (const auto& [name, d] : a.f) csv << "," << fmt(row.drawn.at(name), "%.9g");
    csv << "\n";
  }
}

/// The target class's margin against each parameter's draw (search_margin_<name>.png, whose
/// names it returns) and against the run index (search_progress.png).
std::vector<std::string> write_plots(const std::filesystem::path& dir, const SearchAnalysis& a) {
  const auto colour_of = [&](const Row& row) {
    if (row.margins.failed(a.target)) return kFailure;
    if (row.round == 0) return kNominalRound;
    return a.rounds[static_cast<size_t>(row.round)].estimation ? kEstimateRound : kAdaptRound;
  };
  std::vector<std::string> plots;
  for (const auto& [name, d] : a.f) {
    Chart chart(a.margin_label + " against " + name, name, a.margin_label);
    for (int pass = 0; pass < 2; ++pass) {  // failures drawn last, on top
      for (const Row& row : a.rows) {
        const double m = row.margins.of(a.target);
        if (std::isnan(m) || row.margins.failed(a.target) != (pass == 1)) continue;
        chart.add_points({row.drawn.at(name)}, {m}, colour_of(row), 4);
      }
    }
    chart.add_hline(0.0, cv::Scalar(0, 0, 0), "failure below");
    double lo = d.lowest(), hi = d.highest();
    if (!std::isfinite(lo) || !std::isfinite(hi)) {  // a normal: the range drawn
      lo = std::numeric_limits<double>::infinity();
      hi = -lo;
      for (const Row& row : a.rows) {
        lo = std::min(lo, row.drawn.at(name));
        hi = std::max(hi, row.drawn.at(name));
      }
    }
    if (lo < hi) chart.set_x_limits(lo, hi);
    const std::string file = "search_margin_" + name + ".png";
    chart.save_png((dir / file).string());
    plots.push_back(file);
  }
  {
    Chart chart("Search progress: " + a.margin_label + " of each run", "run index", a.margin_label);
    for (const Row& row : a.rows) {
      const double m = row.margins.of(a.target);
      if (!std::isnan(m)) chart.add_points({static_cast<double>(row.record->index)}, {m}, colour_of(row), 4);
    }
    chart.add_hline(0.0, cv::Scalar(0, 0, 0), "failure below");
    chart.save_png((dir / "search_progress.png").string());
  }
  return plots;
}

/// search_summary.json: the settings, each round, each class's estimates, the failures.
nlohmann::json summary_json(const SearchAnalysis& a) {
  using nlohmann::json;
  json summary;
  summary["scenario"] = a.nominal.name;
  summary["settings"] = a.settings;
  summary["runs"] = a.rows.size();
  summary["rounds"] = json::array();
  for (const CeRound& round : a.rounds) {
    std::int64_t stored = 0, failed = 0;
    for (const Row& row : a.rows) {
      if (row.round != round.index) continue;
      ++stored;
      failed += row.margins.failed(a.target);
    }
    json proposal = json::object();
    for (const auto& [name, q] : round.proposal.parameters) {
      proposal[name] = {{"shifted", distribution_json(q.shifted)}, {"nominal_share", q.nominal_share}};
    }
    summary["rounds"].push_back({{"round", round.index}, {"first_run", round.first_run}, {"runs", round.runs},
                                 {"stored", stored}, {"estimation", round.estimation},
                                 {"level", number_or_null(round.level)}, {"elites", round.elites},
                                 {"failures", failed}, {"nominal_share", round.proposal.nominal_share},
                                 {"least_ratio", round.proposal.least_ratio()}, {"proposal", proposal}});
  }
  summary["estimates"] = json::object();
  for (const auto& [c, e] : a.estimates) {
    json j = estimate_json(e.is);
    j["round"] = e.round;
    j["every_round"] = estimate_json(e.every_round);
    j["nominal_worth"] = e.worth_round;
    j["every_round"]["nominal_worth"] = e.worth_every_round;
    if (e.is.failures == 0) j["zero_failure_upper_95"] = e.bound_round;
    if (e.every_round.failures == 0) j["every_round"]["zero_failure_upper_95"] = e.bound_every_round;
    if (a.plain.count(c)) {
      const auto& p = a.plain.at(c);
      j["plain_monte_carlo"] = {{"runs", p.runs}, {"failures", p.failures}, {"lower_95", p.lower},
                                {"upper_95", p.upper}, {"first_failure_run", p.first_failure}};
    }
    summary["estimates"][failure_class_name(c)] = j;
  }
  summary["failures"] = json::array();
  for (const Row* row : a.failures) summary["failures"].push_back(row->record->index);
  summary["first_failure_run"] = a.failures.empty() ? json(nullptr) : json(a.failures.front()->record->index);
  summary["most_likely_failure_run"] = a.most_likely ? json(a.most_likely->record->index) : json(nullptr);
  return summary;
}

/// report.md's head and its rounds with their proposals.
void write_rounds_md(std::ostream& md, const SearchAnalysis& a, const nlohmann::json& summary, const std::string& dir_text) {
  using nlohmann::json;
  md << "# Rare-event search: " << a.nominal.name << "\n\n";
  md << "Cross-entropy search for **" << failure_class_name(a.target) << "** failures (negative " << a.margin_label
     << "; docs/search.md), seed " << a.settings.at("seed").get<std::string>() << ", budget "
     << a.settings.at("budget") << " runs (" << a.rows.size() << " stored), rounds of " << a.settings.at("round_runs")
     << ", elite fraction " << a.settings.at("elite_fraction") << ", at least " << a.settings.at("estimation_runs")
     << " runs kept for the estimate. Every run: `shelfcross replay " << dir_text << " --run K`.\n\n";
  md << "## Rounds\n\nEach round after round 0 draws a whole run from the nominal with probability s (its nominal "
        "share), else each parameter from its fit mixed with its own nominal at the parameter share s_j; c_k = s + "
        "(1 - s) prod_j s_j is the least q / f anywhere, a run's worth in nominal runs in the zero-failure bound (s = "
        "0 in a search of format 1, which mixed each parameter with its own nominal only).\n\n| round | runs (stored) | fitted to level | elites | "
     << failure_class_name(a.target) << " failures | kind | s | c_k |\n|---|---|---|---|---|---|---|---|\n";
  for (const json& r : summary["rounds"]) {
    md << "| " << r["round"] << " | " << r["runs"] << " (" << r["stored"] << ") | "
       << (r["level"].is_null() ? std::string("- (nominal)") : fmt(r["level"].get<double>())) << " | " << r["elites"]
       << " | " << r["failures"] << " | " << (r["estimation"].get<bool>() ? "estimation" : "adaptation") << " | "
       << fmt(r["nominal_share"].get<double>()) << " | " << fmt(r["least_ratio"].get<double>()) << " |\n";
  }
  md << "\nThe proposals (the fitted component, each parameter mixed with its own nominal at the share s_j of "
        "the summary's rounds):\n\n"
     << "| parameter | nominal |";
  for (const CeRound& round : a.rounds) md << " round " << round.index << " |";
  md << "\n|---|---|";
  for (size_t i = 0; i < a.rounds.size(); ++i) md << "---|";
  md << "\n";
  for (const auto& [name, d] : a.f) {
    md << "| " << name << " | " << describe(d) << " |";
    for (const CeRound& round : a.rounds) {
      const ProposalDistribution& q = round.proposal.parameters.at(name);
      md << " " << (q.nominal_share >= 1.0 ? std::string("nominal") : describe(q.shifted)) << " |";
    }
    md << "\n";
  }
}

/// report.md's failure probabilities: importance sampling from the estimation round and from
/// every round, the zero-failure bound where none failed, plain Monte Carlo beside them.
void write_estimates_md(std::ostream& md, const SearchAnalysis& a, const std::optional<std::filesystem::path>& campaign_dir) {
  md << "\n## Failure probabilities under the nominal dispersions\n\n"
     << "Importance sampling from the runs of round " << a.estimate_round
     << (a.rounds.empty() || !a.rounds.back().estimation ? " (adaptation not finished: the last round's proposal)" : "")
     << ": p_hat = mean of 1[failed] f(x) / q(x); interval: 95 % CLT on the log scale, p_hat exp(-+1.96 se / p_hat) "
        "(rare_event.hpp); the plain CLT interval p_hat -+ 1.96 se beside it; ESS: the failures' effective sample "
        "size (Kish); mean weight: mean f / q over all the round's runs, an unbiased estimate of 1; a mark after "
        "them says why an interval is not to be trusted (weights uneven: mean weight outside [0.5, 2]; few "
        "effective failures: ESS below max(2, 0.3 x failures)).";
  if (campaign_dir) md << " Plain Monte Carlo: the campaign in `" << campaign_dir->string() << "`, failures over runs, two-sided 95 % Clopper-Pearson.";
  md << " The row \"every round\" weighs every stored run of the search as a draw of the mixture of all "
        "the rounds' proposals (multiple importance sampling, balance heuristic: w = f(x) / sum_k (n_k / N) q_k(x); "
        "rare_event.hpp): bounded weights (round 0 is the nominal), and the early rounds cover the edge of a soft "
        "failure region that the final proposal leaves out. Where no run failed, the interval is the one-sided 95 % "
        "zero-failure bound (below).";
  md << "\n\n| class | from | runs | failures | p_hat | 95 % interval | CLT interval | ESS | mean weight |"
     << (campaign_dir ? " plain Monte Carlo | its 95 % interval | its first failure |" : "") << "\n|---|---|---|---|---|---|---|---|---|"
     << (campaign_dir ? "---|---|---|" : "") << "\n";
  // "[lo, hi]", appended piece by piece: GCC 12 misreads "literal" + std::string as an
  // overlapping copy (-Wrestrict, a false positive in its own <string>).
  const auto interval = [](double lo, double hi) {
    std::string text = "[";
    text += fmt(lo);
    text += ", ";
    text += fmt(hi);
    text += ']';
    return text;
  };
  for (const auto& [c, e] : a.estimates) {
    auto row = [&](const IsEstimate& is, const std::string& from, double bound) {
      md << "| " << failure_class_name(c) << " | " << from << " | " << is.runs << " | " << is.failures << " | " << fmt(is.p_hat) << " | "
         << (is.failures ? interval(is.lower, is.upper)
                         : "none sampled: p <= " + fmt(bound) + " (zero-failure bound)")
         << " | " << (is.failures ? interval(is.clt_lower, is.clt_upper) : std::string("-"))
         << " | " << fmt(is.failure_ess, "%.1f") << " | " << fmt(is.mean_weight, "%.3g");
      if (const std::string doubts = estimate_doubts(is); !doubts.empty()) md << " (" << doubts << ")";
      md << " |";
      if (campaign_dir) {
        const auto& p = a.plain.at(c);
        md << " " << p.failures << " / " << p.runs << " | [" << fmt(p.lower) << ", " << fmt(p.upper) << "] | "
           << (p.first_failure >= 0 ? "run " + std::to_string(p.first_failure) : std::string("none")) << " |";
      }
      md << "\n";
    };
    row(e.is, "round " + std::to_string(e.round), e.bound_round);
    row(e.every_round, "every round", e.bound_every_round);
  }
  if (a.estimates.empty()) return;
  const ClassEstimate& any = a.estimates.begin()->second;  // the bound is the same for every class
  md << "\n### The zero-failure bound\n\nEach round k's proposal is at least c_k times the nominal everywhere "
        "(the rounds' table), so a class of nominal probability p fails a run of round k with probability at least "
        "c_k p, wherever its failures lie. The runs of every round are worth sum_k c_k n_k = **"
     << fmt(any.worth_every_round, "%.1f") << " nominal runs** (the estimation round's alone " << fmt(any.worth_round, "%.1f")
     << "): a class none of them failed has **p <= " << fmt(any.bound_every_round)
     << "** (one-sided 95 %: the p at which prod_k (1 - c_k p)^n_k = 0.05; a plain campaign of n runs gives 1 - "
        "0.05^(1/n), about 3 / n). It holds however the proposals were fitted and wherever the search is stopped "
        "(rare_event.hpp). It assumes: the runs' outcomes are the simulation's (a bound on the model under the "
        "scenario's dispersions, not on the world); a run's outcome is a function of its draws and its seed; a run "
        "without the class's margin counts as no failure of it (never near a shelf; a crashed or hung worker: a crash "
        "is trusted to hide no contact); a run lost to a worker error was not lost because it failed.\n";
}

/// report.md's failures of the target class (each with its replay command), the most likely
/// one, and the margin plots.
void write_failures_md(std::ostream& md, const SearchAnalysis& a, const std::vector<std::string>& plots,
                       const std::string& dir_text) {
  md << "\n## Failures found (" << failure_class_name(a.target) << ")\n\n";
  if (a.failures.empty()) {
    md << "None in " << a.rows.size() << " runs.\n";
  } else {
    md << a.failures.size() << " of " << a.rows.size() << " runs; the first is run " << a.failures.front()->record->index
       << ".\n\n| run | round | outcome | margin | log nominal density | replay (with its video) |\n|---|---|---|---|---|---|\n";
    for (const Row* row : a.failures) {
      md << "| " << row->record->index << " | " << row->round << " | " << row->record->outcome << " | "
         << fmt(row->margins.of(a.target)) << " | " << fmt(row->log_nominal) << " | `shelfcross replay " << dir_text
         << " --run " << row->record->index << " --video` |\n";
    }
    md << "\n### The most likely failure: run " << a.most_likely->record->index
       << " (highest nominal density among the failures)\n\n| parameter | drawn | nominal |\n|---|---|---|\n";
    for (const auto& [name, d] : a.f) md << "| " << name << " | " << fmt(a.most_likely->drawn.at(name), "%.6g") << " | " << describe(d) << " |\n";
  }
  md << "\n## Margin against each parameter\n\nWhich parameters separate failures from successes: the "
     << a.margin_label << " of every run against its draw (grey: round 0, the nominal; blue: adaptation rounds; green: "
        "the estimation round; red: failed), and against the run index.\n\n![progress](search_progress.png)\n\n";
  for (const std::string& file : plots) md << "![" << file << "](" << file << ")\n";
  md << "\nEvery run's margins and draws: `margins.csv`.\n";
}

}  // namespace

nlohmann::json write_search_report(const std::filesystem::path& dir, const std::optional<std::filesystem::path>& campaign_dir) {
  const std::filesystem::path db = dir / "results.sqlite";
  const SearchStore search = SearchStore::open_existing(db);
  const ResultsStore store = ResultsStore::open_existing(db);
  SearchAnalysis a;
  a.nominal = parse_scenario(store.meta().scenario_yaml, db.string());
  a.f = ParameterDistributions(a.nominal.dispersions.begin(), a.nominal.dispersions.end());
  a.settings = search.settings_json();
  a.target = parse_failure_class(a.settings.at("target").get<std::string>()).value_or(FailureClass::contact);
  a.margin_label = std::string(failure_class_name(a.target)) + " margin" + (a.target == FailureClass::mission ? "" : " (m)");
  a.rounds = search.rounds();
  a.records = store.runs();
  a.rows = read_rows(a);
  // The estimate: from the estimation round's runs, or the last round's while adaptation goes on.
  a.estimate_round = a.rounds.empty() ? -1 : a.rounds.back().index;
  a.estimates = class_estimates(a);
  if (campaign_dir) a.plain = plain_estimates(a, store.meta().scenario_yaml, *campaign_dir);
  // Failures of the target class, the first one, the most likely one.
  for (const Row& row : a.rows) {
    if (!row.margins.failed(a.target)) continue;
    a.failures.push_back(&row);
    if (!a.most_likely || row.log_nominal > a.most_likely->log_nominal) a.most_likely = &row;
  }

  write_margins_csv(dir, a);
  const std::vector<std::string> plots = write_plots(dir, a);
  const nlohmann::json summary = summary_json(a);
  std::ofstream(dir / "search_summary.json") << summary.dump(2) << "\n";
  std::ostringstream md;
  const std::string dir_text = dir.string();
  write_rounds_md(md, a, summary, dir_text);
  write_estimates_md(md, a, campaign_dir);
  write_failures_md(md, a, plots, dir_text);
  std::ofstream(dir / "report.md") << md.str();
  return summary;
}

}  // namespace shelfcross::verification
