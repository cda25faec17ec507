#include "identify/response_fit.hpp"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <functional>
#include <limits>

#include <Eigen/Dense>

#include "identify/nelder_mead.hpp"
#include "shelfcross/random.hpp"

namespace shelfcross::identify {
namespace {

constexpr std::uint64_t kBootstrapSalt = 0xB0075724A9ull;
constexpr int kGridTau = 24, kGridDelay = 21;

struct Projection {
  double sse = std::numeric_limits<double>::infinity();
  Eigen::VectorXd coefficients;  // gain, then the offsets (integral observation)
};

// For fixed (tau, d): the linear least squares in the gain and the offsets.
Projection project(const AxisRecord& r, const std::vector<double>& y, double tau, double delay) {
  const std::vector<double> s = unit_response(r.input, tau, delay, r.t_s, r.observation, r.loop);
  const int n = static_cast<int>(y.size());
  const int offsets = r.observation == Observation::integral ? r.segments : 0;
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n, 1 + offsets);
  Eigen::VectorXd b(n);
  for (int k = 0; k < n; ++k) {
    A(k, 0) = s[k];
    if (offsets > 0) A(k, 1 + r.segment[k]) = 1.0;
    b(k) = y[k];
  }
  Projection p;
  p.coefficients = A.colPivHouseholderQr().solve(b);
  p.sse = (A * p.coefficients - b).squaredNorm();
  if (!std::isfinite(p.sse)) p.sse = std::numeric_limits<double>::infinity();
  return p;
}

struct Solution {
  double log_tau, delay;
  Projection projection;
};

Solution solve(const AxisRecord& r, const std::vector<double>& y, const FitBounds& b) {
  const double lt_lo = std::log(b.tau_min_s), lt_hi = std::log(b.tau_max_s);
  auto clamp = [&](const std::array<double, 2>& p) {
    return std::array<double, 2>{std::clamp(p[0], lt_lo, lt_hi), std::clamp(p[1], b.delay_min_s, b.delay_max_s)};
  };
  auto cost = [&](const std::vector<double>& v) {
    const std::array<double, 2> p = {v[0], v[1]};
    const auto q = clamp(p);
    // Outside the box: the boundary's cost plus a slope back in, so the simplex returns.
    const double outside = std::abs(p[0] - q[0]) + std::abs(p[1] - q[1]);
    return project(r, y, std::exp(q[0]), q[1]).sse * (1.0 + outside);
  };
  std::array<double, 2> best{};
  {
    // Coarse grid: 24 time constants (log-spaced) x 21 dead times.
    double best_cost = std::numeric_limits<double>::infinity();
    for (int i = 0; i < kGridTau; ++i) {
      for (int j = 0; j < (b.delay_max_s > b.delay_min_s ? kGridDelay : 1); ++j) {
        const std::array<double, 2> p = {lt_lo + (lt_hi - lt_lo) * i / (kGridTau - 1.0),
                                         b.delay_min_s + (b.delay_max_s - b.delay_min_s) * j / (kGridDelay - 1.0)};
        const double c = cost({p[0], p[1]});
        if (c < best_cost) {
          best_cost = c;
          best = p;
        }
      }
    }
  }
  const std::vector<double> step = {(lt_hi - lt_lo) / (kGridTau - 1.0), (b.delay_max_s - b.delay_min_s) / (kGridDelay - 1.0)};
  const std::vector<double> found = nelder_mead(cost, {best[0], best[1]}, step, 200);
  const auto p = clamp({found[0], found[1]});
  return {p[0], p[1], project(r, y, std::exp(p[0]), p[1])};
}

}  // namespace

double log_normal_mass(double a, double b) {
  constexpr double kRoot2 = 1.4142135623730951;
  double mass = 0.0;
  if (a > 0.0) {
    mass = 0.5 * (std::erfc(a / kRoot2) - std::erfc(b / kRoot2));
  } else if (b < 0.0) {
    mass = 0.5 * (std::erfc(-b / kRoot2) - std::erfc(-a / kRoot2));
  } else {
    mass = 1.0 - 0.5 * (std::erfc(-a / kRoot2) + std::erfc(b / kRoot2));
  }
  return std::log(std::max(mass, 1e-300));
}

namespace {

// The reference model and the tracking loop's state, advanced with the input held.
class Response {
 public:
  Response(double tau_s, const TrackingLoop& loop) : tau_(tau_s), loop_(loop) {}

  void advance(double dt, double u) {
    if (loop_.kind == TrackingLoop::Kind::none) {
      // Exact: x -> u + (x - u) e^{-dt/tau}; its integral gains u dt + (x - u) tau (1 - e^{-dt/tau}).
      const double decay = -std::expm1(-dt / tau_);
      p_ += u * dt + (v_ - u) * tau_ * decay;
      v_ += (u - v_) * decay;
      return;
    }
    while (dt > 0.0) {
      const double h = std::min(dt, loop_.step_s);
      tick(h, u);
      dt -= h;
    }
  }
  double velocity() const { return v_; }
  double position() const { return p_; }

 private:
  // One autopilot tick of length h, in control()'s order: the reference model (exact for the
  // tick, a_ff from before the update), then the loops on the state.
  void tick(double h, double u) {
    const double a_ff = (u - v_ref_) / tau_;
    v_ref_ += (u - v_ref_) * -std::expm1(-h / tau_);
    p_ref_ += v_ref_ * h;
    const TrackingLoop& L = loop_;
    if (L.kind == TrackingLoop::Kind::rate) {
      // The rate loop is a PI on the rate error; its output is the angular acceleration.
      const double w_d = v_ref_ + L.pos_gain_per_s * (p_ref_ - p_);
      const double alpha = L.rate_gain_per_s * (w_d - v_) + integral_;
      integral_ += L.rate_integral_gain_per_s2 * (w_d - v_) * h;
      v_ += alpha * h;
      p_ += v_ * h;
      return;
    }
    const double e_v = v_ref_ + L.pos_gain_per_s * (p_ref_ - p_) - v_;
    const double a_cmd = a_ff + L.vel_gain_per_s * e_v + integral_;
    integral_ += L.vel_integral_gain_per_s2 * e_v * h;
    if (L.att_gain_per_s > 0.0) {
      // Tilt (as acceleration, a = g tilt) under the angle loop and the rate loop.
      a_dot_ += h * L.rate_gain_per_s * (L.att_gain_per_s * (a_cmd - a_) - a_dot_);
      a_ += h * a_dot_;
    } else if (L.lag_s > 0.0) {
      a_ += (a_cmd - a_) * -std::expm1(-h / L.lag_s);
    } else {
      a_ = a_cmd;
    }
    v_ += (a_ - L.drag_per_s * v_) * h;
    p_ += v_ * h;
  }

  double tau_;
  TrackingLoop loop_;
  double v_ref_ = 0.0, p_ref_ = 0.0, integral_ = 0.0;
  double a_ = 0.0, a_dot_ = 0.0, v_ = 0.0, p_ = 0.0;
};

}  // namespace

std::vector<double> unit_response(const PiecewiseInput& input, double tau_s, double delay_s,
                                  const std::vector<double>& t_s, Observation observation,
                                  const TrackingLoop& loop) {
  assert(tau_s > 0.0 && input.t_s.size() == input.u.size());
  std::vector<double> out;
  out.reserve(t_s.size());
  if (t_s.empty()) return out;
  Response response(tau_s, loop);
  double u = 0.0;
  double now = t_s.front();
  if (!input.t_s.empty()) now = std::min(now, input.t_s.front() + delay_s);
  auto advance = [&](double to) {
    if (to > now) response.advance(to - now, u);
    now = std::max(now, to);
  };
  size_t i = 0;
  double origin = 0.0;
  for (size_t k = 0; k < t_s.size(); ++k) {
    while (i < input.t_s.size() && input.t_s[i] + delay_s <= t_s[k]) {
      advance(input.t_s[i] + delay_s);
      u = input.u[i++];
    }
    advance(t_s[k]);
    if (k == 0) origin = response.position();  // the integral counts from the first sample
    out.push_back(observation == Observation::direct ? response.velocity() : response.position() - origin);
  }
  return out;
}

namespace {

// The floor on the noise's standard deviation, in quanta (response_fit.hpp): a state record's
// sampling instant is known to within a few ms of its stamp, and the steepest velocity change
// of the calibration is about 1 m/s^2, so a reading's value before rounding is blurred by about
// 0.005 m/s = q / 20 even without noise. A floor of a whole rounding's standard deviation (q /
// sqrt(12)) treats the rounding as noise and pulls every plateau to the middle of its reading:
// on a noise-free record of the plant (the calibration manoeuvre, gain 1, time constant 0.5 s)
// that fitted 0.955 and 0.44 s and a dead time of 0.04 s where the truth is 0.
constexpr double kSigmaFloorQuanta = 0.05;


// The negative log-likelihood of rounded samples y at theta = (K, log tau, d, log(sigma -
// sigma_floor)); outside the search box the bound's value plus a slope back in.
double quantised_nll(const AxisRecord& r, const std::vector<double>& y, const std::vector<double>& theta,
                     const FitBounds& b) {
  const double log_tau = std::clamp(theta[1], std::log(b.tau_min_s), std::log(b.tau_max_s));
  const double delay = std::clamp(theta[2], b.delay_min_s, b.delay_max_s);
  const double outside = std::abs(theta[1] - log_tau) + std::abs(theta[2] - delay);
  const double q = r.quantum;
  const double sigma = kSigmaFloorQuanta * q + std::exp(std::min(theta[3], 5.0));
  const std::vector<double> unit = unit_response(r.input, std::exp(log_tau), delay, r.t_s, r.observation, r.loop);
  double nll = 0.0;
  for (size_t k = 0; k < y.size(); ++k) {
    const double f = theta[0] * unit[k];
    nll -= log_normal_mass((y[k] - q / 2 - f) / sigma, (y[k] + q / 2 - f) / sigma);
  }
  return nll * (1.0 + outside);
}

std::vector<double> fit_quantised(const AxisRecord& r, const std::vector<double>& y, std::vector<double> start,
                                  const std::vector<double>& step, int iterations, const FitBounds& b) {
  std::vector<double> theta =
      nelder_mead([&](const std::vector<double>& t) { return quantised_nll(r, y, t, b); }, std::move(start), step, iterations);
  theta[1] = std::clamp(theta[1], std::log(b.tau_min_s), std::log(b.tau_max_s));
  theta[2] = std::clamp(theta[2], b.delay_min_s, b.delay_max_s);
  return theta;
}

double sigma_of(const AxisRecord& r, double log_excess) {
  return kSigmaFloorQuanta * r.quantum + std::exp(std::min(log_excess, 5.0));
}

}  // namespace

AxisFit fit_axis(const AxisRecord& r, const FitBounds& b) {
  assert(r.t_s.size() == r.y.size() && r.y.size() >= 4);
  const Solution s = solve(r, r.y, b);
  AxisFit f;
  f.tau_s = std::exp(s.log_tau);
  f.delay_s = s.delay;
  f.gain = s.projection.coefficients(0);
  if (r.quantum > 0.0 && r.observation == Observation::direct) {
    // From the least-squares fit, noise at the floor.
    const std::vector<double> theta = fit_quantised(r, r.y, {f.gain, s.log_tau, s.delay, std::log(0.05 * r.quantum)},
                                                    {0.05 * std::max(std::abs(f.gain), 0.1), 0.1, 0.02, 1.0}, 300, b);
    f.gain = theta[0];
    f.tau_s = std::exp(theta[1]);
    f.delay_s = theta[2];
    f.sigma = sigma_of(r, theta[3]);
  }
  for (int i = 1; i < s.projection.coefficients.size(); ++i) f.offsets.push_back(s.projection.coefficients(i));
  const std::vector<double> unit = unit_response(r.input, f.tau_s, f.delay_s, r.t_s, r.observation, r.loop);
  f.fitted.resize(unit.size());
  for (size_t k = 0; k < unit.size(); ++k) f.fitted[k] = f.gain * unit[k] + (f.offsets.empty() ? 0.0 : f.offsets[r.segment[k]]);
  double sse = 0.0;
  for (size_t k = 0; k < unit.size(); ++k) sse += (r.y[k] - f.fitted[k]) * (r.y[k] - f.fitted[k]);
  f.rms = std::sqrt(sse / static_cast<double>(r.y.size()));
  const double tol = 1e-3;
  const bool delay_free = b.delay_max_s > b.delay_min_s;  // a given dead time is no search bound
  f.at_bound = f.tau_s < b.tau_min_s * (1 + tol) || f.tau_s > b.tau_max_s * (1 - tol) ||
               (delay_free && (f.delay_s < b.delay_min_s + tol || f.delay_s > b.delay_max_s - tol));
  return f;
}

Interval interval_of(double value, std::vector<double> replicates) {
  Interval iv;
  iv.value = value;
  if (replicates.empty()) {
    iv.lo = iv.hi = value;
    return iv;
  }
  std::vector<double> sorted = replicates;  // the replicates keep their order (pairing across axes)
  std::sort(sorted.begin(), sorted.end());
  // Percentiles by linear interpolation between order statistics.
  auto pct = [&](double q) {
    const double pos = q * static_cast<double>(sorted.size() - 1);
    const size_t i = static_cast<size_t>(std::floor(pos));
    const size_t j = std::min(i + 1, sorted.size() - 1);
    return sorted[i] + (pos - static_cast<double>(i)) * (sorted[j] - sorted[i]);
  };
  iv.lo = pct(0.025);
  iv.hi = pct(0.975);
  double mean = 0.0;
  for (double v : replicates) mean += v;
  mean /= static_cast<double>(replicates.size());
  double var = 0.0;
  for (double v : replicates) var += (v - mean) * (v - mean);
  iv.stddev = replicates.size() > 1 ? std::sqrt(var / static_cast<double>(replicates.size() - 1)) : 0.0;
  iv.replicates = std::move(replicates);
  return iv;
}

namespace {

// The model K s(tau, d) + offsets at the samples.
Eigen::VectorXd model(const AxisRecord& r, const Eigen::VectorXd& theta) {
  const std::vector<double> unit = unit_response(r.input, theta(1), theta(2), r.t_s, r.observation, r.loop);
  Eigen::VectorXd f(static_cast<Eigen::Index>(unit.size()));
  for (size_t k = 0; k < unit.size(); ++k) {
    f(static_cast<Eigen::Index>(k)) = theta(0) * unit[k] + (theta.size() > 3 ? theta(3 + r.segment[k]) : 0.0);
  }
  return f;
}

// One Gauss-Newton step of the record y from theta = (K, tau, d, offsets...), tau and d's
// columns by central differences, the step kept inside the search box.
Eigen::VectorXd gauss_newton_step(const AxisRecord& r, const Eigen::VectorXd& y, Eigen::VectorXd theta, const FitBounds& b) {
  const Eigen::Index n = y.size(), p = theta.size();
  const Eigen::VectorXd f = model(r, theta);
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(n, p);
  Eigen::VectorXd unit_theta = theta;  // K's column: the unit response, offsets excluded
  unit_theta(0) = 1.0;
  unit_theta.tail(p - 3).setZero();
  J.col(0) = model(r, unit_theta);
  for (Eigen::Index j : {1, 2}) {
    const double h = j == 1 ? 0.01 * theta(1) : 0.005;
    Eigen::VectorXd up = theta, down = theta;
    up(j) += h;
    down(j) -= h;
    J.col(j) = (model(r, up) - model(r, down)) / (2.0 * h);
  }
  for (Eigen::Index k = 0; k < n; ++k) {
    if (p > 3) J(k, 3 + r.segment[static_cast<size_t>(k)]) = 1.0;
  }
  theta += J.colPivHouseholderQr().solve(y - f);
  theta(1) = std::clamp(theta(1), b.tau_min_s, b.tau_max_s);
  theta(2) = std::clamp(theta(2), b.delay_min_s, b.delay_max_s);
  return theta;
}

// The lag-1 autocorrelation of the residuals over pairs of consecutive samples of one segment
// at most max_gap_s apart, clamped to [0, 0.95] (a negative one is no reason for narrower
// intervals; above 0.95 the AR(1) stands for a drift the offsets or the model should take).
double lag1_correlation(const AxisRecord& r, const std::vector<double>& residual, double max_gap_s) {
  double cross = 0.0, square = 0.0;
  for (size_t k = 0; k < residual.size(); ++k) {
    square += residual[k] * residual[k];
    if (k > 0 && r.segment[k] == r.segment[k - 1] && r.t_s[k] - r.t_s[k - 1] <= max_gap_s) {
      cross += residual[k] * residual[k - 1];
    }
  }
  return square > 0.0 ? std::clamp(cross / square, 0.0, 0.95) : 0.0;
}

}  // namespace

AxisIdentification identify_axis(const AxisRecord& r, int replicates, std::uint64_t seed, double block_s,
                                 const FitBounds& b, const std::vector<double>* delay_replicates) {
  AxisIdentification id;
  id.fit = fit_axis(r, b);
  const size_t n = r.y.size();
  std::vector<double> residual(n);
  double mean = 0.0;
  for (size_t k = 0; k < n; ++k) mean += (residual[k] = r.y[k] - id.fit.fitted[k]);
  mean /= static_cast<double>(n);
  for (double& e : residual) e -= mean;
  // Block length in samples from the median sample interval.
  std::vector<double> dts;
  for (size_t k = 1; k < n; ++k) dts.push_back(r.t_s[k] - r.t_s[k - 1]);
  std::nth_element(dts.begin(), dts.begin() + static_cast<long>(dts.size() / 2), dts.end());
  const double dt = dts.empty() || dts[dts.size() / 2] <= 0.0 ? 0.1 : dts[dts.size() / 2];
  const size_t block = std::clamp<size_t>(static_cast<size_t>(std::lround(block_s / dt)), 1, n);
  // The resampling is no source of randomness of a run (StreamId lists those): its own seed,
  // salted apart from run seeds, picks the generator; the stream id only completes the key.
  RandomStream stream(mix64(seed ^ kBootstrapSalt), StreamId::dispersion);
  Eigen::VectorXd theta_hat(3 + static_cast<Eigen::Index>(id.fit.offsets.size()));
  theta_hat << id.fit.gain, id.fit.tau_s, id.fit.delay_s,
      Eigen::Map<const Eigen::VectorXd>(id.fit.offsets.data(), static_cast<Eigen::Index>(id.fit.offsets.size()));
  std::vector<double> gains, taus, delays;
  if (r.quantum > 0.0 && r.observation == Observation::direct) {
    const double q = r.quantum;
    const std::vector<double> start = {id.fit.gain, std::log(id.fit.tau_s), id.fit.delay_s,
                                       std::log(std::max(id.fit.sigma - kSigmaFloorQuanta * q, 1e-6))};
    // The noise of a replicate is AR(1) with the residuals' lag-1 correlation (gusts move the
    // drone for a second or so; independent draws would pretend each reading a new chance).
    const double rho = lag1_correlation(r, residual, 1.5 * dt);
    const double innovation = std::sqrt(1.0 - rho * rho);
    std::vector<double> y(n);
    for (int rep = 0; rep < replicates; ++rep) {
      double e = 0.0;
      for (size_t k = 0; k < n; ++k) {
        const bool continues = k > 0 && r.segment[k] == r.segment[k - 1] && r.t_s[k] - r.t_s[k - 1] <= 1.5 * dt;
        e = continues ? rho * e + innovation * id.fit.sigma * stream.normal() : id.fit.sigma * stream.normal();
        y[k] = q * std::round((id.fit.fitted[k] + e) / q);
      }
      const std::vector<double> theta = fit_quantised(r, y, start, {0.02 * std::max(std::abs(id.fit.gain), 0.1), 0.05, 0.01, 0.5}, 100, b);
      gains.push_back(theta[0]);
      taus.push_back(std::exp(theta[1]));
      delays.push_back(theta[2]);
    }
    id.gain = interval_of(id.fit.gain, std::move(gains));
    id.tau_s = interval_of(id.fit.tau_s, std::move(taus));
    id.delay_s = interval_of(id.fit.delay_s, std::move(delays));
    return id;
  }
  Eigen::VectorXd y(static_cast<Eigen::Index>(n));
  for (int rep = 0; rep < replicates; ++rep) {
    for (size_t k = 0; k < n;) {
      const size_t from = static_cast<size_t>(stream.below(n - block + 1));
      for (size_t j = 0; j < block && k < n; ++j, ++k) {
        y(static_cast<Eigen::Index>(k)) = id.fit.fitted[k] + residual[from + j];
      }
    }
    // The refit: two Gauss-Newton steps from the estimate (the resampled record differs from
    // the fitted one by residual-sized amounts, so the estimate is a close start). A dead time
    // given per replicate is held at that replicate's value.
    FitBounds rb = b;
    Eigen::VectorXd theta = theta_hat;
    if (delay_replicates && !delay_replicates->empty()) {
      rb.delay_min_s = rb.delay_max_s = theta(2) = (*delay_replicates)[static_cast<size_t>(rep) % delay_replicates->size()];
    }
    theta = gauss_newton_step(r, y, theta, rb);
    theta = gauss_newton_step(r, y, theta, rb);
    gains.push_back(theta(0));
    taus.push_back(theta(1));
    delays.push_back(theta(2));
  }
  id.gain = interval_of(id.fit.gain, std::move(gains));
  id.tau_s = interval_of(id.fit.tau_s, std::move(taus));
  id.delay_s = interval_of(id.fit.delay_s, std::move(delays));
  return id;
}

}  // namespace shelfcross::identify
