#pragma once
/// The boundary of a shape as plain arrays: a closed polygon (2D) or a closed triangle surface
/// (3D). This module knows nothing of meshes or PETSc.
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "hypershape/core/random.hpp"

namespace hypershape::geometry {

/// A closed boundary.
///  - dim 2: a simple closed polygon; facets are segments (2 point indices), counter-clockwise,
///    so the outward normal of segment (a, b) is (b - a) rotated clockwise.
///  - dim 3: a closed, 2-manifold triangle surface; facets are triangles (3 point indices) with
///    the right-hand normal pointing outward.
struct Boundary {
  int dim = 0;
  std::vector<double> points;  ///< n_points * dim coordinates
  std::vector<int> facets;     ///< n_facets * dim point indices

  std::int64_t n_points() const { return dim ? std::int64_t(points.size()) / dim : 0; }
  std::int64_t n_facets() const { return dim ? std::int64_t(facets.size()) / dim : 0; }
  /// Coordinates of point i (dim entries).
  std::span<const double> point(std::int64_t i) const {
    return {points.data() + i * dim, std::size_t(dim)};
  }
  /// Point indices of facet f (dim entries).
  std::span<const int> facet(std::int64_t f) const {
    return {facets.data() + f * dim, std::size_t(dim)};
  }
};

/// A closed polygon through `xy` (n * 2 coordinates, counter-clockwise) as a Boundary.
Boundary polygon_boundary(std::vector<double> xy);

/// Length (2D) or area (3D) of facet f.
double facet_measure(const Boundary& b, std::int64_t f);

/// A point drawn uniformly by length / area on the facets of `b`, skipping the facets with
/// `excluded[f] != 0` (none when empty). Draws 2 (2D) or 3 (3D) uniforms from `rng`.
/// Throws std::invalid_argument if no facet is left.
std::array<double, 3> uniform_boundary_point(const Boundary& b, core::RandomStream& rng,
                                             std::span<const std::uint8_t> excluded = {});

/// Scales `b` into [-1, 1]^d: its bounding box centred at the origin, the largest half-extent 1.
void normalise_into_box(Boundary& b);

/// Per boundary point: the mean length of the facet edges through it (the size it is resolved at).
std::vector<double> boundary_spacing(const Boundary& b);

}  // namespace hypershape::geometry
