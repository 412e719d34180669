#pragma once
/// Internal: closest-point and inside/outside queries on the facets of a Boundary.
///
/// This header is CGAL-free on purpose: CGAL lives in exactly one translation unit
/// (src/geometry/distance.cpp, which implements FacetTree), because CGAL TUs are slow to compile.
/// distance.cpp and metrics.cpp both use FacetTree through this interface.
#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <span>
#include <type_traits>

#include "hypershape/geometry/boundary.hpp"

namespace hypershape::geometry::detail {

/// The closest point of a facet set to a query point.
struct ClosestHit {
  std::array<double, 3> point{};  ///< closest point (third entry 0 in 2D)
  std::int64_t facet = -1;        ///< index of its facet in the Boundary; -1: none found
  std::int64_t primitive = -1;    ///< index of the facet inside the tree (for hints)
  double squared_distance = std::numeric_limits<double>::infinity();
};

/// A non-owning callable `bool(std::int64_t facet)` (cheaper than std::function: no allocation).
class FacetFilter {
 public:
  template <class F>
  requires(!std::is_same_v<std::remove_cvref_t<F>, FacetFilter>)
      FacetFilter(const F& f)  // NOLINT: implicit on purpose, like std::function_ref
      : object_(&f), call_([](const void* o, std::int64_t facet) {
          return (*static_cast<const F*>(o))(facet);
        }) {}
  bool operator()(std::int64_t facet) const { return call_(object_, facet); }

 private:
  const void* object_;
  bool (*call_)(const void*, std::int64_t);
};

/// A bounding-volume hierarchy over some facets of a Boundary (segments in 2D, triangles in 3D),
/// with the facet geometry copied in (the Boundary may die). Query points have `dim`
/// coordinates; 2D points are handled as (x, y, 0). Queries do not modify the tree.
class FacetTree {
 public:
  /// Tree over `facets` (indices into `boundary`'s facets; all facets when empty). With
  /// `with_side`, side() is available; it requires `facets` to be the whole closed boundary.
  /// Throws std::invalid_argument for a dimension other than 2/3, no facets, or an index out of
  /// range.
  FacetTree(const Boundary& boundary, std::span<const std::int64_t> facets, bool with_side);
  ~FacetTree();
  FacetTree(FacetTree&&) noexcept;
  FacetTree& operator=(FacetTree&&) noexcept;

  int dim() const { return dim_; }
  /// Diagonal of the bounding box of the facets.
  double bbox_diagonal() const;

  /// Closest point on the facets to x.
  ClosestHit closest(const double* x) const;
  /// Same, starting from `hint`, a previous result of this tree (faster for nearby queries).
  ClosestHit closest(const double* x, const ClosestHit& hint) const;
  /// Closest point to x among the facets f with !skip(f) and squared distance < bound_sq;
  /// facet == -1 when there is none.
  ClosestHit closest_if(const double* x, double bound_sq, FacetFilter skip) const;
  /// Squared distance from x to the facet with tree index `primitive` (ClosestHit::primitive).
  double squared_distance_to(const double* x, std::int64_t primitive) const;
  /// Exact location of x w.r.t. the closed boundary: -1 inside, 0 on it, +1 outside
  /// (exact predicates; needs `with_side`).
  int side(const double* x) const;

  struct Impl;  ///< defined (and derived from) in distance.cpp only

 private:
  int dim_ = 0;
  std::unique_ptr<Impl> impl_;
};

}  // namespace hypershape::geometry::detail
