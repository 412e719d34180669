// Meshes graded towards the ends of a 2D shape's Dirichlet regions, where u is singular.
#include <algorithm>
#include <cmath>
#include <functional>
#include <stdexcept>

#include "hypershape/factory/shape_pipeline.hpp"
#include "hypershape/geometry/boundary.hpp"
#include "hypershape/mesh/boundary_mesher.hpp"

namespace hypershape::factory {

std::vector<std::array<double, 2>> clamp_ends(const ShapeSample& shape) {
  const geometry::Boundary& b = shape.boundary;
  std::vector<int> in_patch(std::size_t(b.n_points()), 0);
  for (int f : shape.dirichlet_facets)
    for (int v : b.facet(f)) ++in_patch[std::size_t(v)];
  std::vector<std::array<double, 2>> ends;
  for (std::size_t v = 0; v < in_patch.size(); ++v)
    if (in_patch[v] == 1) ends.push_back({b.points[2 * v], b.points[2 * v + 1]});
  return ends;
}

namespace {

/// Positions t in [0, 1] that split the segment a -> b into pieces of about size(x) each:
/// equal shares of the integral of 1 / size along it (size linear in the distance to the
/// nearest end, so the pieces grow geometrically away from an end).
std::vector<double> graded_split(const double* a, const double* b, const std::function<double(double, double)>& size) {
  constexpr int samples = 256;
  const double length = std::hypot(b[0] - a[0], b[1] - a[1]);
  std::vector<double> cumulative(samples + 1, 0.0);
  for (int k = 0; k < samples; ++k) {
    const double t = (k + 0.5) / samples;
    cumulative[std::size_t(k + 1)] =
        cumulative[std::size_t(k)] + length / samples / size(a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]));
  }
  const int pieces = std::max(1, int(std::lround(cumulative.back())));
  std::vector<double> t;
  for (int j = 1; j < pieces; ++j) {
    const double want = cumulative.back() * j / pieces;
    const auto k = std::size_t(std::upper_bound(cumulative.begin(), cumulative.end(), want) - cumulative.begin()) - 1;
    const double frac = (want - cumulative[k]) / (cumulative[k + 1] - cumulative[k]);
    t.push_back((double(k) + frac) / samples);
  }
  return t;
}

}  // namespace

ShapeSample grade_shape(const ShapeSample& shape, double h, double end_size, double growth) {
  if (shape.mesh.dim != 2) throw std::invalid_argument("grade_shape: 2D shapes only");
  const auto ends = clamp_ends(shape);
  const auto size = [&](double x, double y) {
    double s = h;
    for (const auto& e : ends) s = std::min(s, end_size + growth * std::hypot(x - e[0], y - e[1]));
    return s;
  };
  const geometry::Boundary& b = shape.boundary;
  std::vector<char> dirichlet(std::size_t(b.n_facets()), 0);
  for (int f : shape.dirichlet_facets) dirichlet[std::size_t(f)] = 1;
  ShapeSample out = shape;
  geometry::Boundary& nb = out.boundary;
  nb.points.clear();
  nb.facets.clear();
  out.dirichlet_facets.clear();
  // Per facet: its start point, then the points that split it (new numbers from `first[f]`).
  std::vector<int> start_of(std::size_t(b.n_points()), -1), first(std::size_t(b.n_facets())), pieces(first.size());
  for (std::int64_t f = 0; f < b.n_facets(); ++f) {
    const auto v = b.facet(f);
    const double* pa = &b.points[2 * std::size_t(v[0])];
    const double* pb = &b.points[2 * std::size_t(v[1])];
    first[std::size_t(f)] = start_of[std::size_t(v[0])] = int(nb.n_points());
    nb.points.insert(nb.points.end(), {pa[0], pa[1]});
    const auto split = graded_split(pa, pb, size);
    for (double t : split) nb.points.insert(nb.points.end(), {pa[0] + t * (pb[0] - pa[0]), pa[1] + t * (pb[1] - pa[1])});
    pieces[std::size_t(f)] = int(split.size()) + 1;
  }
  for (std::int64_t f = 0; f < b.n_facets(); ++f) {
    const int a = first[std::size_t(f)], n = pieces[std::size_t(f)], end = start_of[std::size_t(b.facet(f)[1])];
    for (int k = 0; k < n; ++k) {
      if (dirichlet[std::size_t(f)]) out.dirichlet_facets.push_back(int(nb.n_facets()));
      nb.facets.insert(nb.facets.end(), {a + k, k + 1 < n ? a + k + 1 : end});
    }
  }
  mesh::BoundaryMeshOptions mopt;
  mopt.h = h;
  mopt.point_sizes = geometry::boundary_spacing(nb);
  out.mesh = mesh::mesh_boundary(nb, mopt);
  return out;
}

}  // namespace hypershape::factory
