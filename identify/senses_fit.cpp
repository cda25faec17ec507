#include "identify/senses_fit.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include <Eigen/Dense>

#include "identify/drift_track.hpp"
#include "shelfcross/random.hpp"

namespace shelfcross::identify {
namespace {

constexpr double kSettleAfterTakeoff_s = 3.0;  // the takeoff's climb ends before the hover counts
constexpr double kSettleAfterStick_s = 2.0;    // after a stick returns to centre
constexpr double kBeforeStick_s = 0.5;
constexpr double kBeforePass_s = 3.0, kAfterPass_s = 6.0;
// An edge: between two records the range reading steps by at least kRangeEdgeFraction of the
// board's height (tof's noise is centimetres; the drone's own height moves only through the
// hold's loops, at most 6 cm in a record's period at the manoeuvre's steepest climb), and h - tof
// by at least kEdgeFraction of it the same way (a climb moves h and tof alike). h - tof steps by
// less than the height: the hold's range offset has moved for up to a record's period since the
// edge (beta (1 - exp(-0.1 s / tau)) of it: 0.39 for a hold following wholly with 0.2 s), and
// h's noise is up to a few cm.
constexpr double kRangeEdgeFraction = 0.6, kEdgeFraction = 0.2;
// The SDK's resolutions (docs/tello_sdk.md): h and tof in cm, baro with two decimals, vgx and
// vgy in dm/s.
constexpr double kCm = 0.01, kDm = 0.1;

// The longest stretch of centred sticks while flying (seconds since the takeoff's ok).
std::optional<std::pair<double, double>> still_stretch(const FlightRecord& r) {
  const TimeNs t0 = *r.takeoff_ok_ns;
  const double end_s = ns_to_seconds(r.land_sent_ns.value_or(r.end_ns) - t0);
  std::optional<std::pair<double, double>> best;
  auto close = [&](double from, double to) {
    if (to > from && (!best || to - from > best->second - best->first)) best = std::pair(from, to);
  };
  bool still = true;  // the sticks are centred from the takeoff on until an rc says otherwise
  double from = kSettleAfterTakeoff_s;
  for (const RcSent& rc : r.rc) {
    const double t = ns_to_seconds(rc.t_ns - t0);
    if (t < 0.0 || t > end_s) continue;
    const bool centred = rc.sticks == std::array<int, 4>{};
    if (!centred && still) {
      close(from, t - kBeforeStick_s);
      still = false;
    } else if (centred && !still) {
      from = std::max(kSettleAfterTakeoff_s, t + kSettleAfterStick_s);
      still = true;
    }
  }
  if (still) close(from, end_s - kBeforeStick_s);
  return best;
}

// --- the board pass ---------------------------------------------------------------------------

struct PassData {
  std::vector<double> t_s, y_m;  // y = h - tof - H u
  std::vector<int> window;
  int windows = 0;
  std::vector<double> edge_lo_s, edge_hi_s;  // each edge between two records
  std::vector<double> edge_sign;             // +1 onto the board, -1 off it
  std::vector<double> window_start_s;
  double drift_m_per_sqrt_s = 0.0;  // h - tof's own slow drift over the floor (drift_intensity)
  double baro_walk_m_per_sqrt_s = 0.0;  // the barometer's drift itself, from baro - tof (barometer_walk)
};

// The drift of y = h - tof over the floor, where the hold has settled: (1 - beta) times the
// barometer's drift, a random walk. From the means of 1 s bins, D the change between bins 5 s
// apart: E[D^2] = q^2 5 s + 2 sigma^2 / n (sigma the records' white noise, from consecutive
// differences: E[dy^2] = 2 sigma^2). The hold's own motion and a tilted range reading add to D,
// so q errs large. Over a pass the drift is no line: the bootstrap draws it (bootstrap_pass).
double drift_intensity(const std::vector<double>& t, const std::vector<double>& y, const std::vector<bool>& settled) {
  constexpr double kBin_s = 1.0, kLag_s = 5.0;
  std::map<long, std::pair<double, int>> bins;
  double dy2 = 0.0;
  int pairs = 0;
  for (size_t k = 0; k < t.size(); ++k) {
    if (!settled[k]) continue;
    auto& b = bins[std::lround(std::floor(t[k] / kBin_s))];
    b.first += y[k];
    ++b.second;
    if (k > 0 && settled[k - 1]) {
      dy2 += (y[k] - y[k - 1]) * (y[k] - y[k - 1]);
      ++pairs;
    }
  }
  if (pairs < 10) return 0.0;
  const double sigma2 = dy2 / pairs / 2.0;
  double d2 = 0.0, white = 0.0;
  int n = 0;
  for (const auto& [i, b] : bins) {
    const auto j = bins.find(i + std::lround(kLag_s / kBin_s));
    if (b.second < 5 || j == bins.end() || j->second.second < 5) continue;
    const double d = j->second.first / j->second.second - b.first / b.second;
    d2 += d * d;
    white += sigma2 / b.second + sigma2 / j->second.second;
    ++n;
  }
  if (n < 5) return 0.0;
  return std::sqrt(std::max(0.0, (d2 - white) / n) / kLag_s);
}

// The barometer's drift's own intensity q from w = baro - tof - H u (drift_track.hpp), from
// kWalkLead_s before the first window (the still hover) to the last one's end, the records
// within kWalkEdgeGap_s of an edge left out (the board's rim reads a few cm above its top). 0
// without a barometer.
constexpr double kWalkLead_s = 15.0, kWalkEdgeGap_s = 0.25;
double barometer_walk(const std::vector<double>& t, const std::vector<double>& baro, const std::vector<double>& tof,
                      const std::vector<int>& over, double from_s, double to_s, double H, const PassData& d) {
  std::vector<double> tw, w;
  for (size_t k = 0; k < t.size(); ++k) {
    if (t[k] < from_s - kWalkLead_s || t[k] > to_s || !std::isfinite(baro[k])) continue;
    bool near_edge = false;
    for (size_t j = 0; j < d.edge_lo_s.size(); ++j) {
      near_edge = near_edge || (t[k] >= d.edge_lo_s[j] - kWalkEdgeGap_s && t[k] <= d.edge_hi_s[j] + kWalkEdgeGap_s);
    }
    if (near_edge) continue;
    tw.push_back(t[k]);
    w.push_back(baro[k] - tof[k] - H * over[k]);
  }
  return walk_intensity(tw, w).intensity_m_per_sqrt_s;
}

// F_tau[u] at the records for edges at `edges_s`.
std::vector<double> hold_response(const PassData& d, const std::vector<double>& edges_s, double tau_s) {
  std::vector<double> f(d.t_s.size(), 0.0);
  for (size_t k = 0; k < f.size(); ++k) {
    for (size_t j = 0; j < edges_s.size(); ++j) {
      if (d.t_s[k] >= edges_s[j]) f[k] += d.edge_sign[j] * -std::expm1(-(d.t_s[k] - edges_s[j]) / tau_s);
    }
  }
  return f;
}

struct PassFit {
  double b = 0.0;  // -beta H
  double tau_s = 0.0;
  double rss = 0.0;
  std::vector<double> fitted;
};

// Least squares in (b, offsets, slopes) for one tau.
PassFit fit_at(const PassData& d, const std::vector<double>& y, const std::vector<double>& edges_s, double tau_s) {
  const std::vector<double> f = hold_response(d, edges_s, tau_s);
  const Eigen::Index n = static_cast<Eigen::Index>(y.size());
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n, 1 + 2 * d.windows);
  Eigen::VectorXd b(n);
  for (Eigen::Index k = 0; k < n; ++k) {
    const size_t i = static_cast<size_t>(k);
    A(k, 0) = f[i];
    A(k, 1 + 2 * d.window[i]) = 1.0;
    A(k, 2 + 2 * d.window[i]) = d.t_s[i] - d.window_start_s[static_cast<size_t>(d.window[i])];
    b(k) = y[i];
  }
  const Eigen::VectorXd x = A.colPivHouseholderQr().solve(b);
  const Eigen::VectorXd fitted = A * x;
  PassFit p;
  p.b = x(0);
  p.tau_s = tau_s;
  p.rss = (b - fitted).squaredNorm();
  p.fitted.assign(fitted.data(), fitted.data() + n);
  return p;
}

// tau by a log grid, then golden-section search between the best point's neighbours.
PassFit fit_pass(const PassData& d, const std::vector<double>& y, const std::vector<double>& edges_s) {
  constexpr int kGrid = 60;
  const double l0 = std::log(kTauMin_s), l1 = std::log(kTauMax_s);
  auto at = [&](double log_tau) { return fit_at(d, y, edges_s, std::exp(log_tau)); };
  int best = 0;
  double best_rss = 1e300;
  for (int i = 0; i < kGrid; ++i) {
    const double rss = at(l0 + (l1 - l0) * i / (kGrid - 1)).rss;
    if (rss < best_rss) {
      best_rss = rss;
      best = i;
    }
  }
  double a = l0 + (l1 - l0) * std::max(0, best - 1) / (kGrid - 1);
  double c = l0 + (l1 - l0) * std::min(kGrid - 1, best + 1) / (kGrid - 1);
  constexpr double kPhi = 0.6180339887498949;
  double x1 = c - kPhi * (c - a), x2 = a + kPhi * (c - a);
  double f1 = at(x1).rss, f2 = at(x2).rss;
  for (int it = 0; it < 40; ++it) {
    if (f1 < f2) {
      c = x2;
      x2 = x1;
      f2 = f1;
      x1 = c - kPhi * (c - a);
      f1 = at(x1).rss;
    } else {
      a = x1;
      x1 = x2;
      f1 = f2;
      x2 = a + kPhi * (c - a);
      f2 = at(x2).rss;
    }
  }
  return at(0.5 * (a + c));
}

// The pass's records: y = h - tof, the edges (steps of about +-H between two records), the
// windows. Returns why not, or nothing.
std::optional<std::string> pass_data(const FlightRecord& r, double H, PassData& d, BoardPassFit& out) {
  const std::vector<TimeNs> sent = state_send_times(r);
  const TimeNs t0 = *r.takeoff_ok_ns;
  const double end_s = ns_to_seconds(r.land_sent_ns.value_or(r.end_ns) - t0);
  std::vector<double> t, y, tof, baro;
  for (size_t k = 0; k < r.states.size(); ++k) {
    const double tk = ns_to_seconds(sent[k] - t0);
    if (tk < kSettleAfterTakeoff_s || tk > end_s || !r.states[k].tof_m) continue;
    t.push_back(tk);
    tof.push_back(*r.states[k].tof_m);
    y.push_back(r.states[k].height_m - tof.back());
    baro.push_back(r.states[k].baro_m.value_or(std::numeric_limits<double>::quiet_NaN()));
  }
  std::vector<int> over(t.size(), 0);
  bool on = false;
  for (size_t k = 1; k < t.size(); ++k) {
    const double step = y[k] - y[k - 1], range_step = tof[k - 1] - tof[k];
    if (!on && step >= kEdgeFraction * H && range_step >= kRangeEdgeFraction * H) on = true;
    else if (on && step <= -kEdgeFraction * H && range_step <= -kRangeEdgeFraction * H) on = false;
    else {
      over[k] = on ? 1 : 0;
      continue;
    }
    d.edge_lo_s.push_back(t[k - 1]);
    d.edge_hi_s.push_back(t[k]);
    d.edge_sign.push_back(on ? 1.0 : -1.0);
    out.steps_m.push_back(tof[k - 1] - tof[k]);
    over[k] = on ? 1 : 0;
  }
  if (d.edge_sign.empty()) {
    return "no step of h - tof by about the board's height (" + std::to_string(H) +
           " m) while flying: the range sensor never saw the board (no pass over it, or not where the flight was told)";
  }
  double mean_step = 0.0;
  for (double s : out.steps_m) mean_step += std::abs(s) / static_cast<double>(out.steps_m.size());
  if (std::abs(mean_step - H) > std::max(0.05, 0.2 * H)) {
    return "the range reading stepped by " + std::to_string(mean_step) + " m at the board's edges, not by its stated height " +
           std::to_string(H) + " m: check the height given, and that nothing else lay on the path";
  }
  // Windows: from kBeforePass_s before a pass's first edge to kAfterPass_s after its last.
  std::vector<std::pair<double, double>> spans;
  // A pass: from an edge onto the board to the edge off it (the first edge may be off it, the
  // last onto it); windows that overlap merge.
  for (size_t j = 0; j < d.edge_sign.size(); ++j) {
    const bool continues = d.edge_sign[j] < 0.0 && j > 0 && d.edge_sign[j - 1] > 0.0;
    const double from = d.edge_lo_s[j] - kBeforePass_s, to = d.edge_hi_s[j] + kAfterPass_s;
    if (!spans.empty() && (continues || from <= spans.back().second)) spans.back().second = to;
    else spans.push_back({from, to});
  }
  for (size_t k = 0; k < t.size(); ++k) {
    for (size_t w = 0; w < spans.size(); ++w) {
      if (t[k] < spans[w].first || t[k] > spans[w].second) continue;
      d.t_s.push_back(t[k]);
      d.y_m.push_back(y[k] - H * over[k]);
      d.window.push_back(static_cast<int>(w));
    }
  }
  // Settled over the floor: not over the board, and kAfterPass_s after leaving it.
  std::vector<bool> settled(t.size());
  for (size_t k = 0; k < t.size(); ++k) {
    settled[k] = over[k] == 0;
    for (size_t j = 0; j < d.edge_sign.size(); ++j) {
      if (d.edge_sign[j] < 0.0 && t[k] >= d.edge_lo_s[j] && t[k] <= d.edge_hi_s[j] + kAfterPass_s) settled[k] = false;
    }
  }
  d.drift_m_per_sqrt_s = drift_intensity(t, y, settled);
  d.baro_walk_m_per_sqrt_s = barometer_walk(t, baro, tof, over, spans.front().first, spans.back().second, H, d);
  d.windows = static_cast<int>(spans.size());
  for (const auto& s : spans) d.window_start_s.push_back(s.first);
  return std::nullopt;
}

std::vector<double> middles(const PassData& d) {
  std::vector<double> e;
  for (size_t j = 0; j < d.edge_lo_s.size(); ++j) e.push_back(0.5 * (d.edge_lo_s[j] + d.edge_hi_s[j]));
  return e;
}

// Moving blocks of the residuals within each window, onto the fit; edges drawn anew.
void bootstrap_pass(const PassData& d, const PassFit& fit, double H, const SensesOptions& o, std::vector<double>& betas,
                    std::vector<double>& taus) {
  RandomStream rng(mix64(o.seed + 0x5E45E5), StreamId::sensor_noise);
  std::vector<double> residual(d.y_m.size());
  for (size_t k = 0; k < residual.size(); ++k) residual[k] = d.y_m[k] - fit.fitted[k];
  const int block = std::max(1, static_cast<int>(std::lround(o.block_s / 0.1)));
  // y - H u holds the barometer's drift as d - beta F_tau[d]: the hold follows it too. Over the
  // floor's 5 s lags (drift_intensity) that is about (1 - beta) d, but within a time constant the
  // hold has not yet followed and y moves with d's whole intensity (a plain walk of the floor's
  // (1 - beta) q would be a tenth of it at beta = 0.9). d's own intensity q: the
  // floor's over (1 - beta); where the hold follows more than half, the floor shows less than
  // half of d (nothing at beta = 1) and the barometer's own track (baro - tof, noisier: its
  // noise is the barometer's) counts too, the larger of the two (beta at most 0.8 in the ratio).
  const double beta = std::clamp(-fit.b / H, 0.0, 1.0);
  double q = d.drift_m_per_sqrt_s / std::max(0.2, 1.0 - beta);
  if (beta > 0.5) q = std::max(q, d.baro_walk_m_per_sqrt_s);
  std::vector<std::vector<size_t>> members(static_cast<size_t>(d.windows));
  for (size_t k = 0; k < d.window.size(); ++k) members[static_cast<size_t>(d.window[k])].push_back(k);
  for (int b = 0; b < o.bootstrap_replicates; ++b) {
    std::vector<double> y(d.y_m.size());
    for (const auto& m : members) {
      const size_t n = m.size(), len = std::min<size_t>(static_cast<size_t>(block), n);
      for (size_t filled = 0; filled < n;) {
        const size_t start = static_cast<size_t>(rng.below(n - len + 1));
        for (size_t i = 0; i < len && filled < n; ++i, ++filled) y[m[filled]] = fit.fitted[m[filled]] + residual[m[start + i]];
      }
      // A drift drawn anew: the barometer's walk d* and the hold's answer to it,
      // d* - beta F_tau[d*] (from rest at the window's start; the drift held between records).
      double walk = 0.0, followed = 0.0;
      for (size_t i = 1; i < n; ++i) {
        const double dt = std::max(0.0, d.t_s[m[i]] - d.t_s[m[i - 1]]);
        followed += (walk - followed) * -std::expm1(-dt / fit.tau_s);
        walk += q * std::sqrt(dt) * rng.normal();
        y[m[i]] += walk - beta * followed;
      }
    }
    std::vector<double> edges;
    for (size_t j = 0; j < d.edge_lo_s.size(); ++j) edges.push_back(rng.uniform(d.edge_lo_s[j], d.edge_hi_s[j]));
    const PassFit f = fit_pass(d, y, edges);
    betas.push_back(-f.b / H);
    taus.push_back(f.tau_s);
  }
}

void identify_height_hold(const FlightRecord& r, const SensesOptions& o, SensesIdentification& s) {
  const std::string blend = "height_hold_range_blend", tau = "height_hold_time_constant_s";
  if (!o.board_height_m) {
    s.not_identified[blend] = s.not_identified[tau] = "no board height given (--board-height): the height hold's answer to a "
                                                      "step of the range reading needs the board the drone passed over";
    return;
  }
  const double H = *o.board_height_m;
  PassData d;
  if (auto why = pass_data(r, H, d, s.board)) {
    s.not_identified[blend] = s.not_identified[tau] = *why;
    return;
  }
  const PassFit fit = fit_pass(d, d.y_m, middles(d));
  std::vector<double> betas, taus;
  bootstrap_pass(d, fit, H, o, betas, taus);
  Interval beta = interval_of(-fit.b / H, std::move(betas));
  s.how[blend] = "h - tof across " + std::to_string(d.edge_sign.size()) + " edges of the board";
  s.board.t_s = d.t_s;
  s.board.y_m = d.y_m;
  s.board.fitted_m = fit.fitted;
  s.board.edges_s = middles(d);
  s.board.window = d.window;
  double rss = 0.0;
  for (size_t k = 0; k < d.y_m.size(); ++k) rss += (d.y_m[k] - fit.fitted[k]) * (d.y_m[k] - fit.fitted[k]);
  s.board.rms_m = std::sqrt(rss / static_cast<double>(std::max<size_t>(1, d.y_m.size())));
  Interval t = interval_of(fit.tau_s, std::move(taus));
  if (beta.lo <= kFollowsFrom) {
    s.not_identified[tau] = "the hold follows the range reading too little to time it (range_blend's interval reaches " +
                            std::to_string(beta.lo) + ")";
  } else if (t.hi >= kTauIdentifiableBelow_s) {
    s.not_identified[tau] = "too slow to time within the pass (the interval reaches " + std::to_string(t.hi) + " s)";
  } else {
    s.parameters[tau] = std::move(t);
    s.how[tau] = s.how[blend];
  }
  s.parameters[blend] = std::move(beta);
}

// --- the still hover --------------------------------------------------------------------------

void identify_noises(const FlightRecord& r, const SensesOptions& o, SensesIdentification& s) {
  const auto stretch = still_stretch(r);
  const std::vector<std::string> names = {"height_noise_m", "baro_noise_m", "tof_noise_m", "vps_noise_mps"};
  if (!stretch || stretch->second - stretch->first < o.min_still_s) {
    for (const auto& n : names) {
      s.not_identified[n] = "no still hover of " + std::to_string(o.min_still_s) +
                            " s or more (every stick centred while flying): fly the senses block (--senses-board)";
    }
    return;
  }
  s.still_found = true;
  s.still_from_s = stretch->first;
  s.still_to_s = stretch->second;
  const std::vector<TimeNs> sent = state_send_times(r);
  // One series per reading, broken where a reading is missing.
  std::array<std::vector<std::vector<double>>, 5> series;  // h, baro, tof, vgx, vgy
  auto add = [&](size_t i, const std::optional<double>& v) {
    if (!v) {
      if (!series[i].empty() && !series[i].back().empty()) series[i].emplace_back();
      return;
    }
    if (series[i].empty()) series[i].emplace_back();
    series[i].back().push_back(*v);
  };
  for (size_t k = 0; k < r.states.size(); ++k) {
    const double t = ns_to_seconds(sent[k] - *r.takeoff_ok_ns);
    if (t < stretch->first || t > stretch->second) continue;
    const StateRecord& st = r.states[k];
    ++s.still_records;
    add(0, st.height_m);
    add(1, st.baro_m);
    add(2, st.tof_m);
    add(3, st.vx_H_mps);
    add(4, st.vy_H_mps);
  }
  auto put = [&](const std::string& name, const std::vector<std::vector<double>>& parts, double q, bool bound) {
    size_t n = 0;
    for (const auto& p : parts) n += p.size();
    if (n < 20) {
      s.not_identified[name] = "fewer than 20 readings in the still hover";
      return;
    }
    const RoundedNoise fit = fit_rounded_noise(parts, q, o.half_window);
    Interval iv;
    iv.value = fit.sigma;
    iv.lo = bound ? 0.0 : fit.lo;
    iv.hi = fit.hi;
    iv.stddev = (fit.hi - fit.lo) / (2.0 * 1.96);
    s.parameters[name] = iv;
    s.how[name] = std::string(bound ? "upper bound: " : "") + "scatter of " + std::to_string(n) +
                  " readings in the still hover (n_eff " + std::to_string(static_cast<int>(std::lround(fit.n_eff))) + ")";
  };
  put("height_noise_m", series[0], kCm, false);
  put("baro_noise_m", series[1], kCm, false);
  put("tof_noise_m", series[2], kCm, false);
  std::vector<std::vector<double>> v = series[3];
  v.insert(v.end(), series[4].begin(), series[4].end());
  put("vps_noise_mps", v, kDm, true);
}

}  // namespace

const std::vector<std::string>& senses_parameter_names() {
  static const std::vector<std::string> names = {"vps_noise_mps", "height_noise_m", "baro_noise_m", "tof_noise_m",
                                                 "height_hold_range_blend", "height_hold_time_constant_s"};
  return names;
}

SensesIdentification identify_senses(const FlightRecord& r, const SensesOptions& o) {
  SensesIdentification s;
  s.board_height_m = o.board_height_m;
  if (!r.takeoff_ok_ns) {
    for (const auto& n : senses_parameter_names()) s.not_identified[n] = "no flight";
    return s;
  }
  identify_noises(r, o, s);
  identify_height_hold(r, o, s);
  s.not_identified["vps_bias_stddev_mps"] =
      "not identifiable from a log: the hold flies the VPS's estimate, so vgx and vgy read about 0 whatever its bias, and the "
      "drift it causes is in no reading";
  s.not_identified["baro_drift_m_per_sqrt_s"] = "not identified: millimetres over the still hover, under the baro's noise";
  return s;
}

}  // namespace shelfcross::identify
