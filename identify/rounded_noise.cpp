#include "identify/senses_fit.hpp"

#include <algorithm>
#include <cmath>

#include "identify/response_fit.hpp"

// fit_rounded_noise (senses_fit.hpp): the noise of rounded readings about their moving mean.
namespace shelfcross::identify {
namespace {

constexpr double kChiSquare95 = 3.841458820694124;  // 1 degree of freedom

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

}  // namespace shelfcross::identify
