#pragma once
// How much the lens bends, by distance from the optical axis: the statistics the meshes bound
// their chords and interiors with (lens_mesh.hpp draws along the lens grid, edge_mesh.hpp along
// a face's own edges). Made by make_lens_grids (lens_mesh.cpp) on its 4 px lattice.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <vector>

#include <Eigen/Core>

namespace shelfcross::render {

/// The lens's statistics over the region, for bounds on segments and triangles anywhere in
/// it, by distance from the optical axis: bin k holds the statistics of every lattice point
/// of make_lens_grids (4 px pitch) with |(x, y)| < (k + 1) step, so a box is bounded by the
/// bin of its farthest corner (plus two bins: the lattice points up to one pitch beyond the
/// box, as for the grids' cells). The lens is nearly radial (the tangential terms are small),
/// so this costs little over a bound per box, and a look-up is one division.
struct LensStats {
  struct Stats {
    double Mf = 0.0;  ///< max |D''(e, e)| over unit e, pixels per squared normalised unit
    double Mp = 0.0;  ///< max |n(e) . D''(e, e)|, n(e) the unit normal of J e
    double Jmin = std::numeric_limits<double>::infinity();  ///< min |J e|
    void merge(const Stats& o) {
      Mf = std::max(Mf, o.Mf), Mp = std::max(Mp, o.Mp), Jmin = std::min(Jmin, o.Jmin);
    }
  };
  double step = 0.0;            ///< bin width (the lattice pitch), normalised units
  std::vector<Stats> by_radius;  ///< bin k: every lattice point with radius < (k + 1) step
  /// An upper bound on Mf, Mp and a lower bound on Jmin over the box.
  Stats over(double x0, double x1, double y0, double y1) const {
    const double rx = std::max(std::abs(x0), std::abs(x1)), ry = std::max(std::abs(y0), std::abs(y1));
    const double k = std::sqrt(rx * rx + ry * ry) / step + 2.0;
    const double last = static_cast<double>(by_radius.size() - 1);
    return by_radius[static_cast<std::size_t>(k < last ? k : last)];
  }
  /// Bound (2) of lens_mesh.hpp: how far (output pixels) the image of segment a-b may lie
  /// across its chord.
  double across_chord_px(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const;
  /// Bound on how far (output pixels) the lens image of a point of triangle a b c may lie from
  /// the affine interpolation of its corners' images: Mf r^2 / 2, r the radius of the
  /// smallest disc holding the triangle (Waldron's bound for linear interpolation; r = L / 2
  /// for a segment gives bound (1)).
  double interior_px(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) const;
};

}  // namespace shelfcross::render
