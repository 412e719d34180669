#pragma once
/// Where an effect acts on the boundary, from its keys: `box: [x0, y0, (z0,) x1, y1, (z1)]`
/// (an axis-aligned box, lower corner then upper corner) or `center: [...]` with `radius: r`
/// (a ball). A facet is in the region when all its vertices are (to 1e-9 of the region's
/// size), so a box of zero width selects the facets on a straight edge or plane.
#include <vector>

#include "hypershape/core/params.hpp"
#include "hypershape/physics/effect.hpp"

namespace hypershape::physics {

class Region {
 public:
  /// The whole boundary.
  Region() = default;
  static Region box(std::vector<double> lower, std::vector<double> upper);
  static Region ball(std::vector<double> center, double radius);
  /// Reads box or center + radius (at most one of them); neither: the whole boundary unless
  /// `required`. Errors name the key.
  static Region from_params(const core::Params& p, int dim, bool required);

  bool contains(const double* x, int dim) const;
  /// The facets whose vertices are all in the region.
  FacetPredicate facets() const;
  bool everywhere() const { return kind_ == Kind::all; }

 private:
  enum class Kind { all, box, ball };
  Kind kind_ = Kind::all;
  std::vector<double> a_, b_;  ///< box: lower, upper; ball: centre, {radius}
  double tol_ = 0;
};

/// The keys above for help lines.
const char* region_help();

}  // namespace hypershape::physics
