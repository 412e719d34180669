#include "hypershape/geometry/boundary.hpp"

namespace hypershape::geometry {

Boundary polygon_boundary(std::vector<double> xy) {
  Boundary b;
  b.dim = 2;
  b.points = std::move(xy);
  const int n = int(b.n_points());
  b.facets.resize(std::size_t(2 * n));
  for (int i = 0; i < n; ++i) {
    b.facets[2 * i] = i;
    b.facets[2 * i + 1] = (i + 1) % n;
  }
  return b;
}

}  // namespace hypershape::geometry
