#include "hypershape/geometry/boundary.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

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

double facet_measure(const Boundary& b, std::int64_t f) {
  const auto v = b.facet(f);
  const auto p = b.point(v[0]), q = b.point(v[1]);
  if (b.dim == 2) return std::hypot(q[0] - p[0], q[1] - p[1]);
  const auto r = b.point(v[2]);
  const double u[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]};
  const double w[3] = {r[0] - p[0], r[1] - p[1], r[2] - p[2]};
  return 0.5 * std::sqrt(std::pow(u[1] * w[2] - u[2] * w[1], 2) + std::pow(u[2] * w[0] - u[0] * w[2], 2) +
                         std::pow(u[0] * w[1] - u[1] * w[0], 2));
}

std::array<double, 3> uniform_boundary_point(const Boundary& b, core::RandomStream& rng,
                                             std::span<const std::uint8_t> excluded) {
  const std::int64_t n = b.n_facets();
  if (!excluded.empty() && std::int64_t(excluded.size()) != n)
    throw std::invalid_argument("uniform_boundary_point: mask size != number of facets");
  std::vector<double> cumulative(std::size_t(n) + 1, 0.0);
  for (std::int64_t f = 0; f < n; ++f) {
    const bool skip = !excluded.empty() && excluded[std::size_t(f)];
    cumulative[std::size_t(f) + 1] = cumulative[std::size_t(f)] + (skip ? 0.0 : facet_measure(b, f));
  }
  if (!(cumulative.back() > 0)) throw std::invalid_argument("uniform_boundary_point: no facet to draw from");
  const double target = rng.uniform() * cumulative.back();
  const auto it = std::upper_bound(cumulative.begin(), cumulative.end(), target);
  std::int64_t f = std::clamp<std::int64_t>(it - cumulative.begin() - 1, 0, n - 1);
  while (cumulative[std::size_t(f) + 1] == cumulative[std::size_t(f)]) --f;  // never an excluded facet
  const auto v = b.facet(f);
  std::array<double, 3> x{};
  if (b.dim == 2) {
    const double t = rng.uniform();
    for (int a = 0; a < 2; ++a) x[a] = (1 - t) * b.point(v[0])[a] + t * b.point(v[1])[a];
  } else {
    double s = rng.uniform(), t = rng.uniform();
    if (s + t > 1.0) s = 1.0 - s, t = 1.0 - t;
    for (int a = 0; a < 3; ++a)
      x[a] = (1 - s - t) * b.point(v[0])[a] + s * b.point(v[1])[a] + t * b.point(v[2])[a];
  }
  return x;
}

void normalise_into_box(Boundary& b) {
  const int d = b.dim;
  double lo[3], hi[3];
  for (int a = 0; a < d; ++a) lo[a] = std::numeric_limits<double>::infinity(), hi[a] = -lo[a];
  for (std::size_t i = 0; i < b.points.size(); i += d)
    for (int a = 0; a < d; ++a) lo[a] = std::min(lo[a], b.points[i + a]), hi[a] = std::max(hi[a], b.points[i + a]);
  double half = 0.0;
  for (int a = 0; a < d; ++a) half = std::max(half, 0.5 * (hi[a] - lo[a]));
  for (std::size_t i = 0; i < b.points.size(); i += d)
    for (int a = 0; a < d; ++a) b.points[i + a] = (b.points[i + a] - 0.5 * (lo[a] + hi[a])) / half;
}

std::vector<double> boundary_spacing(const Boundary& b) {
  std::vector<double> sum(std::size_t(b.n_points()), 0.0), count(sum.size(), 0.0);
  const int d = b.dim;
  for (std::int64_t f = 0; f < b.n_facets(); ++f) {
    const auto v = b.facet(f);
    for (int e = 0; e < d; ++e) {
      const int i = v[e], j = v[(e + 1) % d];
      if (d == 2 && e == 1) break;  // a segment has one edge
      double l2 = 0.0;
      for (int a = 0; a < d; ++a) l2 += std::pow(b.point(i)[a] - b.point(j)[a], 2);
      const double l = std::sqrt(l2);
      sum[i] += l, sum[j] += l, count[i] += 1, count[j] += 1;
    }
  }
  for (std::size_t i = 0; i < sum.size(); ++i) sum[i] = count[i] > 0 ? sum[i] / count[i] : 0.0;
  return sum;
}

}  // namespace hypershape::geometry
