#include "identify/senses_fit.hpp"

#include <algorithm>
#include <cmath>
#include <map>

#include <Eigen/Dense>

#include "shelfcross/random.hpp"

namespace shelfcross::identify {
namespace {

constexpr double kSettleAfterTakeoff_s = 3.0;  // the takeoff's climb ends before the hover counts
constexpr double kSettleAfterStick_s = 2.0;    // after a stick returns to centre
constexpr double kBeforeStick_s = 0.5;
constexpr double kChiSquare95 = 3.841458820694124;  // 1 degree of freedom
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

// The residuals' autocorrelation at lags 1..max_lag, pooled over the series.
std::vector<double> autocorrelations(const std::vector<std::vector<double>>& residuals, int max_lag) {
  std::vector<double> num(static_cast<size_t>(max_lag) + 1, 0.0);
  for (const auto& r : residuals) {
    for (size_t k = 0; k < r.size(); ++k) {
      for (size_t l = 0; l <= static_cast<size_t>(max_lag) && k + l < r.size(); ++l) num[l] += r[k] * r[k + l];
    }
  }
  std::vector<double> rho(num.size(), 0.0);
  for (size_t l = 1; l < num.size() && num[0] > 0.0; ++l) rho[l] = num[l] / num[0];
  return rho;
}

// The leave-one-out residuals of white readings are correlated by construction: r = W y with
// W_kk = 1 and W_kj = -1/n_k over the record's neighbours, so Cov(r) = sigma^2 W W^T; its
// correlations rho_ij = (W W^T)_ij / sqrt(v_i v_j), v_k = 1 + 1/n_k (lag 1 at half_window 3:
// -0.19, all lags up to 2 half_window non-zero). Returns sum_ij rho_ij^2 over one series.
double structural_correlation_sum(size_t size, int half_window) {
  const int n = static_cast<int>(size), reach = 2 * half_window;
  std::vector<int> lo(size), hi(size);
  for (int k = 0; k < n; ++k) {
    lo[static_cast<size_t>(k)] = std::max(0, k - half_window);
    hi[static_cast<size_t>(k)] = std::min(n - 1, k + half_window);
  }
  auto weight = [&](int k, int j) {  // W_kj
    if (j == k) return 1.0;
    const size_t i = static_cast<size_t>(k);
    if (j < lo[i] || j > hi[i]) return 0.0;
    return -1.0 / (hi[i] - lo[i]);
  };
  auto cov = [&](int a, int b) {  // (W W^T)_ab
    double c = 0.0;
    for (int j = std::max(lo[static_cast<size_t>(a)], lo[static_cast<size_t>(b)]);
         j <= std::min(hi[static_cast<size_t>(a)], hi[static_cast<size_t>(b)]); ++j) {
      c += weight(a, j) * weight(b, j);
    }
    return c;
  };
  double sum = 0.0;
  for (int a = 0; a < n; ++a) {
    const double va = cov(a, a);
    for (int b = std::max(0, a - reach); b <= std::min(n - 1, a + reach); ++b) {
      const double c = cov(a, b);
      sum += c * c / (va * cov(b, b));
    }
  }
  return sum;
}

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

// Leave-one-out moving means and the residuals about them, with each residual's n.
void residuals_about_mean(const std::vector<double>& y, int half_window, std::vector<double>& r, std::vector<int>& n) {
  r.assign(y.size(), 0.0);
  n.assign(y.size(), 0);
  const int size = static_cast<int>(y.size());
  for (int k = 0; k < size; ++k) {
    double sum = 0.0;
    int count = 0;
    for (int j = std::max(0, k - half_window); j <= std::min(size - 1, k + half_window); ++j) {
      if (j == k) continue;
      sum += y[static_cast<size_t>(j)];
      ++count;
    }
    n[static_cast<size_t>(k)] = count;
    r[static_cast<size_t>(k)] = count > 0 ? y[static_cast<size_t>(k)] - sum / count : 0.0;
  }
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
  std::vector<double> t, y, tof;
  for (size_t k = 0; k < r.states.size(); ++k) {
    const double tk = ns_to_seconds(sent[k] - t0);
    if (tk < kSettleAfterTakeoff_s || tk > end_s || !r.states[k].tof_m) continue;
    t.push_back(tk);
    tof.push_back(*r.states[k].tof_m);
    y.push_back(r.states[k].height_m - tof.back());
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
      // A drift drawn anew: a random walk of the intensity the floor showed.
      double walk = 0.0;
      for (size_t i = 1; i < n; ++i) {
        walk += d.drift_m_per_sqrt_s * std::sqrt(std::max(0.0, d.t_s[m[i]] - d.t_s[m[i - 1]])) * rng.normal();
        y[m[i]] += walk;
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

RoundedNoise fit_rounded_noise(const std::vector<std::vector<double>>& series, double q, int half_window) {
  std::vector<std::vector<double>> res(series.size());
  std::vector<std::vector<int>> counts(series.size());
  RoundedNoise out;
  double spread = 0.0;
  for (size_t i = 0; i < series.size(); ++i) {
    residuals_about_mean(series[i], half_window, res[i], counts[i]);
    for (double r : res[i]) spread += r * r;
    out.n += static_cast<int>(series[i].size());
  }
  spread = std::sqrt(spread / std::max(1, out.n));
  auto loglik = [&](double sigma) {
    double l = 0.0;
    for (size_t i = 0; i < res.size(); ++i) {
      for (size_t k = 0; k < res[i].size(); ++k) {
        const double n = std::max(1, counts[i][k]);
        const double se = std::sqrt(sigma * sigma * (1.0 + 1.0 / n) + q * q / (12.0 * n));
        l += log_normal_mass((res[i][k] - q / 2) / se, (res[i][k] + q / 2) / se);
      }
    }
    return l;
  };
  // sigma on a grid from 0 (then q / 500) to well beyond the residuals' spread.
  std::vector<double> grid = {0.0};
  const double top = std::max(3.0 * q, 5.0 * spread);
  constexpr int kGrid = 160;
  for (int i = 0; i < kGrid; ++i) grid.push_back(q / 500.0 * std::pow(top / (q / 500.0), i / (kGrid - 1.0)));
  std::vector<double> ll(grid.size());
  for (size_t i = 0; i < grid.size(); ++i) ll[i] = loglik(grid[i]);
  const size_t best = static_cast<size_t>(std::max_element(ll.begin(), ll.end()) - ll.begin());
  // Golden-section refinement between the best point's neighbours.
  double a = grid[best == 0 ? 0 : best - 1], c = grid[std::min(best + 1, grid.size() - 1)];
  for (int it = 0; it < 50; ++it) {
    const double m1 = a + (c - a) / 3.0, m2 = c - (c - a) / 3.0;
    if (loglik(m1) < loglik(m2)) a = m1;
    else c = m2;
  }
  out.sigma = 0.5 * (a + c);
  const double lmax = std::max(loglik(out.sigma), ll[best]);
  // The log-likelihood treats the n residuals as independent; its curvature then claims
  // Var(sigma^2 estimate) = 2 sigma^4 / n. For Gaussian residuals of correlations rho_ij,
  //     Var(sum_k r_k^2 / v_k) = 2 sigma^4 sum_ij rho_ij^2,
  // so the likelihood is scaled by n_eff / n, n_eff = n^2 / sum_ij rho_ij^2 (the variance of a
  // scatter, which squares the correlations; the mean's n (1 - rho) / (1 + rho) is not it: it
  // ignores the negative correlation the moving mean itself makes, 1.30 times the claimed
  // variance for white readings at half_window 3, and overstates a positive one). sum_ij
  // rho_ij^2 is the larger of the moving mean's own (white readings, exact) and the residuals'
  // sample autocorrelations at lags up to 2 half_window + 1 (each rho_l^2 less its 1 / n bias):
  // a wander the mean leaves behind counts through the latter.
  const int max_lag = 2 * half_window + 1;
  const std::vector<double> rho = autocorrelations(res, max_lag);
  out.rho = std::max(0.0, rho[1]);
  double structural = 0.0, sample = static_cast<double>(out.n);
  for (const auto& r : res) structural += structural_correlation_sum(r.size(), half_window);
  for (int l = 1; l <= max_lag; ++l) {
    sample += 2.0 * out.n * (rho[static_cast<size_t>(l)] * rho[static_cast<size_t>(l)] - 1.0 / out.n);
  }
  const double scale = out.n / std::max({structural, sample, static_cast<double>(out.n)});
  out.n_eff = out.n * scale;
  // The likelihood-ratio interval at n_eff: where 2 scale (lmax - l) = 3.84, by bisection
  // between grid points.
  auto inside = [&](double sigma) { return 2.0 * scale * (lmax - loglik(sigma)) <= kChiSquare95; };
  auto edge = [&](double in, double out_) {
    for (int it = 0; it < 50; ++it) {
      const double m = 0.5 * (in + out_);
      (inside(m) ? in : out_) = m;
    }
    return in;
  };
  out.lo = 0.0;
  for (size_t i = best; i-- > 0;) {
    if (!inside(grid[i])) {
      out.lo = edge(grid[i + 1] <= out.sigma ? grid[i + 1] : out.sigma, grid[i]);
      break;
    }
  }
  out.hi = grid.back();
  for (size_t i = best + 1; i < grid.size(); ++i) {
    if (!inside(grid[i])) {
      out.hi = edge(std::max(grid[i - 1], out.sigma), grid[i]);
      break;
    }
  }
  // Under half a rounding step the readings cannot tell a noise from the rounding of the slow
  // wander: a few flips of the last digit are either (records of known noise and a wander of
  // 0.15 steps: the likelihood's interval missed noises of 0.1 to 0.2 steps in 20 to 40 % of
  // records). The interval then runs from 0 to at least half a step.
  if (out.sigma < 0.5 * q) {
    out.lo = 0.0;
    out.hi = std::max(out.hi, 0.5 * q);
  }
  return out;
}

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
