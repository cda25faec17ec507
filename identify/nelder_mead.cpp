#include "identify/nelder_mead.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <numeric>

namespace shelfcross::identify {

std::vector<double> nelder_mead(const std::function<double(const std::vector<double>&)>& f, std::vector<double> start,
                                const std::vector<double>& step, int iterations) {
  const size_t n = start.size();
  assert(step.size() == n && n > 0);
  std::vector<std::vector<double>> v(n + 1, start);
  for (size_t i = 0; i < n; ++i) v[i + 1][i] += step[i];
  std::vector<double> fv(n + 1);
  for (size_t i = 0; i <= n; ++i) fv[i] = f(v[i]);
  std::vector<size_t> order(n + 1);
  for (int it = 0; it < iterations; ++it) {
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return fv[a] < fv[b]; });
    const size_t best = order.front(), worst = order.back(), second = order[n - 1];
    double spread = 0.0;
    for (size_t i = 0; i < n; ++i) spread = std::max(spread, std::abs(v[worst][i] - v[best][i]));
    if (std::abs(fv[worst] - fv[best]) <= 1e-12 * (1.0 + std::abs(fv[best])) && spread < 1e-7) break;
    std::vector<double> c(n, 0.0);  // centroid of all but the worst
    for (size_t k = 0; k < n; ++k) {
      for (size_t i = 0; i < n; ++i) c[i] += v[order[k]][i] / static_cast<double>(n);
    }
    auto along = [&](double a) {
      std::vector<double> p(n);
      for (size_t i = 0; i < n; ++i) p[i] = c[i] + a * (v[worst][i] - c[i]);
      return p;
    };
    const auto r = along(-1.0);
    const double fr = f(r);
    if (fr < fv[best]) {
      const auto e = along(-2.0);
      const double fe = f(e);
      if (fe < fr) {
        v[worst] = e;
        fv[worst] = fe;
      } else {
        v[worst] = r;
        fv[worst] = fr;
      }
    } else if (fr < fv[second]) {
      v[worst] = r;
      fv[worst] = fr;
    } else {
      const auto k = along(fr < fv[worst] ? -0.5 : 0.5);
      const double fk = f(k);
      if (fk < std::min(fr, fv[worst])) {
        v[worst] = k;
        fv[worst] = fk;
      } else {  // shrink toward the best
        for (size_t j = 0; j <= n; ++j) {
          if (j == best) continue;
          for (size_t i = 0; i < n; ++i) v[j][i] = (v[j][i] + v[best][i]) / 2.0;
          fv[j] = f(v[j]);
        }
      }
    }
  }
  const size_t best = static_cast<size_t>(std::min_element(fv.begin(), fv.end()) - fv.begin());
  return v[best];
}

}  // namespace shelfcross::identify
