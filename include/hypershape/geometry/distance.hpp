#pragma once
/// Distances to a Boundary: signed distance to the whole boundary, unsigned distance to a
/// subset of its facets. Both build a bounding-volume hierarchy once and answer point queries in
/// about O(log n_facets); CGAL (exact predicates, Epick kernel) stays inside the .cpp.
#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <span>

#include "hypershape/geometry/boundary.hpp"

namespace hypershape::geometry {

namespace detail {
class FacetTree;
}

/// The closest point of a boundary to a query point.
struct ClosestPoint {
  double distance = std::numeric_limits<double>::infinity();  ///< unsigned, >= 0
  std::int64_t facet = -1;        ///< index of the facet it lies on (into Boundary::facets)
  std::array<double, 3> point{};  ///< its coordinates (third entry 0 in 2D)
};

/// Signed distance to a closed boundary (2D polygon or 3D triangle surface): negative inside,
/// positive outside, 0 on the boundary.
///
/// The magnitude is the Euclidean distance to the closest facet (segment or triangle), exact to
/// round-off. The sign is decided with exact predicates (CGAL filtered arithmetic): a
/// winding-number test in 2D, a ray-parity test in 3D that re-shoots a ray whenever it meets an
/// edge or a vertex. A point exactly on the boundary gets 0.
///
/// The object copies the geometry it needs; the Boundary may die. Queries keep no mutable state,
/// so one object may serve several threads. Cost (measured, Release, one core): a 128^2 grid
/// around a 2000-segment polygon in ~0.01 s; a 64^3 grid around a 20k-triangle surface in
/// ~0.8 s. Serial, no MPI.
class SignedDistance {
 public:
  /// Builds the trees. Throws std::invalid_argument if `boundary.dim` is not 2 or 3, if it has
  /// no facets or if a facet refers to a missing point. The boundary is assumed closed and
  /// consistently oriented (see Boundary); that is not checked.
  explicit SignedDistance(const Boundary& boundary);
  ~SignedDistance();
  SignedDistance(SignedDistance&&) noexcept;
  SignedDistance& operator=(SignedDistance&&) noexcept;

  /// Dimension of the boundary (2 or 3).
  int dim() const;
  /// Signed distance at x (`dim` coordinates), in the units of the boundary coordinates.
  double operator()(std::span<const double> x) const;
  /// Batched: `points` holds n * dim coordinates, `out` n values. Faster than n calls for
  /// spatially coherent points (each query starts from the previous answer).
  void evaluate(std::span<const double> points, std::span<double> out) const;

  /// Exact location of x (`dim` coordinates): -1 inside, 0 on the boundary, +1 outside; the
  /// sign of operator() without the distance.
  int side(std::span<const double> x) const;
  /// Closest point of the boundary to x (`dim` coordinates). When several facets are equally
  /// close (x on the medial axis, or the closest point a shared vertex or edge), one of them.
  /// Degenerate facets (zero length / area) are never returned.
  ClosestPoint closest(std::span<const double> x) const;
  /// Batched: `points` holds n * dim coordinates, `out` n results. Faster than n calls for
  /// spatially coherent points (each query starts from the previous answer).
  void closest(std::span<const double> points, std::span<ClosestPoint> out) const;

 private:
  std::unique_ptr<detail::FacetTree> tree_;
};

/// Unsigned distance to a subset of the facets of a boundary (e.g. the facets of a clamped
/// patch). The subset need not be closed or connected.
///
/// The object copies the geometry it needs; the Boundary may die. Queries keep no mutable state.
class FacetSetDistance {
 public:
  /// `facets` are indices into `boundary`'s facets (duplicates allowed). Throws
  /// std::invalid_argument if `facets` is empty, an index is out of range, or `boundary.dim` is
  /// not 2 or 3.
  FacetSetDistance(const Boundary& boundary, std::span<const std::int64_t> facets);
  ~FacetSetDistance();
  FacetSetDistance(FacetSetDistance&&) noexcept;
  FacetSetDistance& operator=(FacetSetDistance&&) noexcept;

  /// Dimension of the boundary (2 or 3).
  int dim() const;
  /// Distance from x (`dim` coordinates) to the closest facet of the subset.
  double operator()(std::span<const double> x) const;
  /// Batched: `points` holds n * dim coordinates, `out` n values.
  void evaluate(std::span<const double> points, std::span<double> out) const;

 private:
  std::unique_ptr<detail::FacetTree> tree_;
};

}  // namespace hypershape::geometry
