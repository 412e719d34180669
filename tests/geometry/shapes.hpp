#pragma once
// Test shapes for tests/geometry (built here, not with the library, so that the tests do not
// depend on the code they check).
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numbers>
#include <utility>
#include <vector>

#include "hypershape/geometry/boundary.hpp"

namespace hypershape::geometry::test {

/// Regular n-gon of circumradius r, counter-clockwise, first vertex at angle `phase`.
inline Boundary regular_polygon(int n, double r, double phase = 0.0) {
  std::vector<double> xy;
  for (int i = 0; i < n; ++i) {
    const double t = phase + 2 * std::numbers::pi * i / n;
    xy.push_back(r * std::cos(t));
    xy.push_back(r * std::sin(t));
  }
  return polygon_boundary(std::move(xy));
}

/// Star with `n_spikes` spikes: r(t) = 0.8 + 0.4 cos(n_spikes t) (+ a small wobble), n vertices.
inline Boundary star_polygon(int n_spikes, int n) {
  std::vector<double> xy;
  for (int i = 0; i < n; ++i) {
    const double t = 2 * std::numbers::pi * i / n;
    const double r = 0.8 + 0.4 * std::cos(n_spikes * t) + 0.03 * std::sin(3 * t);
    xy.push_back(r * std::cos(t) + 0.05);
    xy.push_back(r * std::sin(t) - 0.03);
  }
  return polygon_boundary(std::move(xy));
}

/// Axis-aligned rectangle [x0, x1] x [y0, y1] with each side split into pieces of length <= h.
inline Boundary rectangle(double x0, double y0, double x1, double y1, double h) {
  std::vector<double> xy;
  const std::array<std::array<double, 2>, 4> c = {{{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}}};
  for (int s = 0; s < 4; ++s) {
    const auto& a = c[std::size_t(s)];
    const auto& b = c[std::size_t((s + 1) % 4)];
    const int m = std::max(1, int(std::ceil(std::hypot(b[0] - a[0], b[1] - a[1]) / h - 1e-9)));
    for (int k = 0; k < m; ++k) {
      xy.push_back(a[0] + (b[0] - a[0]) * k / m);
      xy.push_back(a[1] + (b[1] - a[1]) * k / m);
    }
  }
  return polygon_boundary(std::move(xy));
}

/// Unit icosphere: an icosahedron whose faces are split in 4 `n_subdivisions` times, every
/// vertex projected onto the unit sphere; outward orientation.
inline Boundary icosphere(int n_subdivisions) {
  const double t = (1 + std::sqrt(5.0)) / 2;
  std::vector<std::array<double, 3>> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                                          {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                                          {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::array<int, 3>> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                       {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                       {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                       {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  const auto project = [](std::array<double, 3> p) {
    const double n = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    return std::array<double, 3>{p[0] / n, p[1] / n, p[2] / n};
  };
  for (auto& p : v) p = project(p);
  for (int s = 0; s < n_subdivisions; ++s) {
    std::map<std::pair<int, int>, int> mid;
    const auto midpoint = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      const auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      const auto& p = v[std::size_t(a)];
      const auto& q = v[std::size_t(b)];
      v.push_back(project({p[0] + q[0], p[1] + q[1], p[2] + q[2]}));
      return mid[key] = int(v.size()) - 1;
    };
    std::vector<std::array<int, 3>> g;
    for (const auto& [a, b, c] : f) {
      const int ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
      g.push_back({a, ab, ca});
      g.push_back({b, bc, ab});
      g.push_back({c, ca, bc});
      g.push_back({ab, bc, ca});
    }
    f = std::move(g);
  }
  Boundary b;
  b.dim = 3;
  for (const auto& p : v) b.points.insert(b.points.end(), p.begin(), p.end());
  for (const auto& t : f) b.facets.insert(b.facets.end(), t.begin(), t.end());
  return b;
}

/// The icosphere mapped radially by a non-convex bump and scaled anisotropically: a closed,
/// star-shaped, non-convex surface that fits in [-1.1, 1.1]^3.
inline Boundary bumpy_surface(int n_subdivisions) {
  Boundary b = icosphere(n_subdivisions);
  for (std::size_t i = 0; i < b.points.size(); i += 3) {
    double* p = &b.points[i];
    const double bump = 0.75 + 0.3 * std::sin(3 * p[0]) * std::cos(2 * p[1]) + 0.2 * p[2] * p[2];
    p[0] *= 1.1 * bump;
    p[1] *= 0.9 * bump;
    p[2] *= 0.8 * bump;
  }
  return b;
}

/// Scaled copy (about the origin).
inline Boundary scaled(Boundary b, double s) {
  for (double& x : b.points) x *= s;
  return b;
}

/// Axis-aligned box [lo, hi], 12 triangles, outward.
inline Boundary box_surface(std::array<double, 3> lo, std::array<double, 3> hi) {
  Boundary b;
  b.dim = 3;
  for (int i = 0; i < 8; ++i) {
    b.points.push_back(i & 1 ? hi[0] : lo[0]);
    b.points.push_back(i & 2 ? hi[1] : lo[1]);
    b.points.push_back(i & 4 ? hi[2] : lo[2]);
  }
  // Corner i has bits (x, y, z). Each face as two triangles, counter-clockwise seen from outside.
  b.facets = {0, 2, 3, 0, 3, 1,   // z = lo
              4, 5, 7, 4, 7, 6,   // z = hi
              0, 1, 5, 0, 5, 4,   // y = lo
              2, 6, 7, 2, 7, 3,   // y = hi
              0, 4, 6, 0, 6, 2,   // x = lo
              1, 3, 7, 1, 7, 5};  // x = hi
  return b;
}

}  // namespace hypershape::geometry::test
