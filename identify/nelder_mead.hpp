#pragma once
// Nelder-Mead minimisation (Nelder & Mead 1965; the standard reflection 1, expansion 2,
// contraction 1/2, shrink 1/2), for the few smooth parameters of a response fit.

#include <functional>
#include <vector>

namespace shelfcross::identify {

/// Minimises f from `start`, the first simplex spanning `step` along each axis; stops after
/// `iterations` or once the simplex has collapsed (values and vertices within 1e-12 relative,
/// 1e-7 absolute). Returns the best vertex. `step` must be as long as `start`, and both
/// non-empty (asserted).
std::vector<double> nelder_mead(const std::function<double(const std::vector<double>&)>& f, std::vector<double> start,
                                const std::vector<double>& step, int iterations);

}  // namespace shelfcross::identify
