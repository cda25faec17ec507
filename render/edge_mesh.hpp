#pragma once
// Flat faces meshed along their own edges (lens_mesh.hpp draws marker and tag faces along the
// lens grid instead).
//
// A face without texture shows one colour, so what its triangles must get right is where its
// edges fall, and, where it is depth-tested, its depth. Its outline in the normalised plane
// (pinhole image, clipped to the lens region) is a convex polygon; each edge a-b is cut into
// the fewest equal parts k for which bound (2) of lens_mesh.hpp, with the lens statistics
// over each part (LensStats), is at most the tolerance: every drawn chord lies within the
// tolerance of the true curve D(a + t (b - a)). The cut points a + (i / k) (b - a) are points
// of the edge (a line stays a line in the normalised plane), so they are projected exactly
// like any vertex. (Equal parts rather than halving: an edge that needs 3 parts gets 3, not 4.)
//
// No cracks: an edge is cut from its end points in a canonical order (lexicographically
// smaller first), so two faces of one solid that share an edge get the same points on it,
// bit for bit, and neither has a point the other lacks (no T-junction).
//
// The interior: the outline's image (the points through the lens, in pixels) is a simple
// polygon, convex up to the tolerance; the lens may bend an edge inward, so it is triangulated
// by ear clipping, which needs no convexity: an ear (a convex vertex whose triangle holds no
// other vertex) is cut off, the one with the shortest new side first (strips along thin faces
// rather than fans across them). The triangles then cover exactly the image polygon of the
// outline, whatever shape it has. Where the face is depth-tested, its interpolated depth is
// off by the interior bound of each triangle (LensStats::interior_px); the mesher accepts the
// outline's triangles only where that bound holds (lens_mesh.cpp).

#include <vector>

#include <Eigen/Core>

#include "render/lens_stats.hpp"

namespace shelfcross::render {

/// Appends to `out` the outline of the polygon `poly` (normalised plane, in order around its
/// edge) with every edge cut into the fewest equal parts whose LensStats::across_chord_px is
/// at most tolerance_px: each corner, then the cut points of the edge that starts there, in
/// order.
void bisect_outline(const LensStats& stats, double tolerance_px, const std::vector<Eigen::Vector2d>& poly,
                    std::vector<Eigen::Vector2d>& out);

/// Triangulates the simple polygon `p` (in order around its edge, either orientation) by ear
/// clipping, shortest new side first: appends index triples into p, each in the polygon's
/// orientation, to `triangles` (p.size() - 2 of them; none when the polygon has no area).
/// Deterministic: the same points give the same triangles.
void triangulate_polygon(const std::vector<Eigen::Vector2d>& p, std::vector<int>& triangles);

}  // namespace shelfcross::render
