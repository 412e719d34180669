#pragma once
/// Isotropic remeshing of a closed triangle surface, optionally drawing the Dirichlet patch
/// boundary (the curve where the surface meets a clamp sphere) into the mesh first.
#include <array>
#include <functional>
#include <optional>
#include <vector>

#include "hypershape/geometry/boundary.hpp"

namespace hypershape::geometry {

/// Controls for remesh_surface.
struct RemeshOptions {
  double target_edge = 0;  ///< target edge length (> 0), in the units of the coordinates
  int iterations = 3;      ///< split/collapse/flip/relax/project rounds (>= 1)
  /// Centre p_D of the clamp sphere |x - p_D| = clamp_radius (on or near the surface), if any.
  std::optional<std::array<double, 3>> clamp_center;
  double clamp_radius = 0;  ///< radius r of the clamp sphere (> 0 when clamp_center is set)
  /// Optional local refinement: the wanted edge length at a point (only where it is below
  /// target_edge matters). After the uniform remesh, the faces whose centroid wants an edge
  /// below 1.5 t are remeshed at t, for t = target_edge / 2, / 4, ... while any face wants it
  /// and t >= min_edge; the vertices this adds (off the clamp curve) are projected onto the
  /// input surface, so a refined patch of a coarse sphere lies on the sphere, not on its chords.
  std::function<double(const std::array<double, 3>&)> size;
  double min_edge = 1e-3;  ///< smallest refinement level (> 0)
};

/// Remeshes a closed, outward-oriented triangle surface (one that passes check_boundary) into
/// near-equilateral triangles with edges of about `opt.target_edge` (CGAL
/// Polygon_mesh_processing::isotropic_remeshing; new vertices are projected onto the input
/// surface, so the result stays on it).
///
/// With a clamp sphere, the surface is first cut along |x - p_D| = r: edges longer than
/// 4/3 target_edge are bisected, vertices within 1e-3 * target_edge of the sphere are snapped
/// onto it, every edge that crosses the sphere is split at its exact crossing point (an edge
/// that dips into the ball first at its point closest to p_D), and the triangles are split, so
/// that the patch boundary is a polyline of mesh edges whose vertices lie on the sphere. Those
/// edges are remeshed as constraints (edge_is_constrained_map, protect_constraints(false)):
/// never flipped or smoothed, only collapsed onto one of their ends; they are too short to be
/// split, and should the remesher still split one, the new vertex is moved to where the input
/// surface meets the sphere. Afterwards every vertex of the patch curve is on the sphere to
/// round-off, every facet of the patch has all its vertices in the closed ball (facets_in_ball
/// returns exactly the patch) and every other facet has a vertex outside it. If the sphere does
/// not cut the surface, no curve is drawn. A clamp radius below target_edge gives a curve of
/// only a few vertices.
///
/// Returns a closed, manifold, outward-oriented surface with compact point numbering. Throws
/// std::invalid_argument for dim != 3, bad options, or a surface that is not a closed 2-manifold
/// (run check_boundary first for the precise reason), and std::runtime_error if moving a curve
/// vertex onto the sphere would fold a triangle (a target edge far too coarse for the clamp
/// radius). Deterministic; not collective.
Boundary remesh_surface(const Boundary& surface, const RemeshOptions& opt);

/// Indices of the facets whose vertices all satisfy |x - center| <= radius * (1 + 1e-9): the
/// Dirichlet patch. Works for dim 2 (segments; center[2] ignored) and dim 3. Ascending order.
std::vector<int> facets_in_ball(const Boundary& b, const std::array<double, 3>& center,
                                double radius);

}  // namespace hypershape::geometry
