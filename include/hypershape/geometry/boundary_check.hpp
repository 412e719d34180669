#pragma once
/// Validity of a Boundary: is it a simple counter-clockwise polygon (2D) or one closed,
/// 2-manifold, outward-oriented, non-self-intersecting triangle surface (3D)?
#include <string>

#include "hypershape/geometry/boundary.hpp"

namespace hypershape::geometry {

/// Outcome of check_boundary.
struct BoundaryCheck {
  bool ok = false;     ///< true when the boundary is valid
  std::string reason;  ///< empty when ok; otherwise the first problem found, as one sentence
                       ///< with numbers, e.g. "open surface: 12 boundary edges (first at
                       ///< point 431)" or "self-intersecting polygon: segments 3 and 77 intersect"
};

/// Checks that `b` is a valid closed boundary, stopping at the first problem found.
///
/// dim 2, in this order: at least 3 points and segments; indices in range; finite coordinates;
/// no zero-length segment (repeated point); every point starts exactly one segment and ends
/// exactly one (so it is used by exactly two); the segments form one cycle; no two segments meet
/// other than consecutive ones at their shared point (exact predicates; a sweep over bounding
/// boxes, O(n log n) for reasonable polygons); positive signed area (counter-clockwise).
///
/// dim 3, in this order: at least 4 triangles; indices in range; finite coordinates; every point
/// used; no degenerate (zero-area) triangle; closed (every edge in exactly two triangles, else
/// "open surface" or "non-manifold edge"); consistently oriented (each edge traversed once in
/// each direction); vertex-manifold (the triangles around a point form one fan); one connected
/// component; positive enclosed volume (outward normals); no self-intersection (exact
/// predicates, CGAL Polygon_mesh_processing::self_intersections).
///
/// Facets and points are named by their 0-based index in `b`. Not collective; pure. Cost: a few
/// milliseconds for a 5000-gon, a few tenths of a second for 100k triangles (mostly the
/// self-intersection test).
BoundaryCheck check_boundary(const Boundary& b);

}  // namespace hypershape::geometry
