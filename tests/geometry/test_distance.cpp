// SignedDistance / FacetSetDistance against brute force: every facet visited, plain textbook
// point-segment / point-triangle distances, and the sign from an independent test (winding angle
// sum in 2D, solid angle sum in 3D).
#include <algorithm>
#include <array>
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <ctime>
#include <iostream>
#include <memory>
#include <numbers>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "geometry/shapes.hpp"
#include "hypershape/geometry/distance.hpp"

namespace hg = hypershape::geometry;
using V3 = std::array<double, 3>;

namespace {

V3 sub(const V3& a, const V3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
V3 add_scaled(const V3& a, const V3& b, double s) {
  return {a[0] + s * b[0], a[1] + s * b[1], a[2] + s * b[2]};
}
double dot(const V3& a, const V3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
V3 cross(const V3& a, const V3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double norm(const V3& a) { return std::sqrt(dot(a, a)); }

V3 point(const hg::Boundary& b, std::int64_t i) {
  const auto p = b.point(i);
  return {p[0], p[1], b.dim == 3 ? p[2] : 0.0};
}

double point_segment_distance(const V3& p, const V3& a, const V3& b) {
  const V3 ab = sub(b, a);
  const double t = std::clamp(dot(sub(p, a), ab) / dot(ab, ab), 0.0, 1.0);
  return norm(sub(p, add_scaled(a, ab, t)));
}

// Closest point on triangle abc (Ericson, Real-Time Collision Detection, 5.1.5), by Voronoi
// regions of the vertices, edges and face.
double point_triangle_distance(const V3& p, const V3& a, const V3& b, const V3& c) {
  const V3 ab = sub(b, a), ac = sub(c, a), ap = sub(p, a);
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return norm(ap);
  const V3 bp = sub(p, b);
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return norm(bp);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return norm(sub(p, add_scaled(a, ab, d1 / (d1 - d3))));
  const V3 cp = sub(p, c);
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return norm(cp);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return norm(sub(p, add_scaled(a, ac, d2 / (d2 - d6))));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0)
    return norm(sub(p, add_scaled(b, sub(c, b), (d4 - d3) / ((d4 - d3) + (d5 - d6)))));
  const double denom = 1 / (va + vb + vc);
  return norm(sub(p, add_scaled(add_scaled(a, ab, vb * denom), ac, vc * denom)));
}

double brute_distance(const hg::Boundary& b, const V3& p, const std::vector<std::int64_t>& facets) {
  double d = HUGE_VAL;
  for (const std::int64_t f : facets) {
    const auto v = b.facet(f);
    d = std::min(
        d, b.dim == 2 ? point_segment_distance(p, point(b, v[0]), point(b, v[1]))
                      : point_triangle_distance(p, point(b, v[0]), point(b, v[1]), point(b, v[2])));
  }
  return d;
}

// Winding number (2D: sum of turning angles / 2pi) or solid angle / 4pi (3D, Van Oosterom and
// Strackee): 1 inside, 0 outside.
double winding(const hg::Boundary& b, const V3& p) {
  double sum = 0;
  for (std::int64_t f = 0; f < b.n_facets(); ++f) {
    const auto v = b.facet(f);
    const V3 x = sub(point(b, v[0]), p), y = sub(point(b, v[1]), p);
    if (b.dim == 2) {
      sum += std::atan2(x[0] * y[1] - x[1] * y[0], x[0] * y[0] + x[1] * y[1]);
    } else {
      const V3 z = sub(point(b, v[2]), p);
      const double lx = norm(x), ly = norm(y), lz = norm(z);
      sum += 2 * std::atan2(dot(x, cross(y, z)),
                            lx * ly * lz + dot(x, y) * lz + dot(y, z) * lx + dot(z, x) * ly);
    }
  }
  return sum / (b.dim == 2 ? 2 * std::numbers::pi : 4 * std::numbers::pi);
}

std::vector<std::int64_t> all_facets(const hg::Boundary& b) {
  std::vector<std::int64_t> f(static_cast<std::size_t>(b.n_facets()));
  for (std::int64_t i = 0; i < b.n_facets(); ++i) f[std::size_t(i)] = i;
  return f;
}

std::vector<double> random_points(int dim, int n, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  std::vector<double> x(std::size_t(dim * n));
  for (double& c : x) c = u(rng);
  return x;
}

// Checks SignedDistance on `n` random points in [-1.5, 1.5]^d against brute force; returns the
// number of inside points (so the caller can check that both signs were exercised).
int check_against_brute_force(const hg::Boundary& b, int n, unsigned seed) {
  const hg::SignedDistance sd(b);
  const int dim = b.dim;
  const std::vector<double> x = random_points(dim, n, seed);
  std::vector<double> batched(static_cast<std::size_t>(n));
  sd.evaluate(x, batched);
  const auto facets = all_facets(b);
  int n_inside = 0;
  for (int i = 0; i < n; ++i) {
    const std::span<const double> xi(x.data() + i * dim, std::size_t(dim));
    const V3 p = {xi[0], xi[1], dim == 3 ? xi[2] : 0.0};
    const double w = winding(b, p);
    REQUIRE((std::abs(w) < 1e-6 || std::abs(w - 1) < 1e-6));  // clear of the boundary
    const bool inside = w > 0.5;
    n_inside += inside;
    const double expected = (inside ? -1 : 1) * brute_distance(b, p, facets);
    const double d = sd(xi);
    INFO("point " << i << " (" << p[0] << ", " << p[1] << ", " << p[2] << ")");
    CHECK(d == Approx(expected).margin(1e-12).epsilon(0));
    CHECK(batched[std::size_t(i)] == d);
  }
  return n_inside;
}

}  // namespace

TEST_CASE("signed distance to a non-convex polygon matches brute force", "[geometry][distance]") {
  const hg::Boundary star = hg::test::star_polygon(7, 350);
  const int n_inside = check_against_brute_force(star, 2500, 1);
  CHECK(n_inside > 300);
  CHECK(n_inside < 2200);

  const hg::SignedDistance sd(star);
  CHECK(sd.dim() == 2);
  SECTION("points on the boundary give 0, shrunk vertices are inside") {
    for (std::int64_t i = 0; i < star.n_points(); ++i) {
      const auto v = star.point(i);
      CHECK(sd(v) == 0.0);  // vertices lie exactly on the boundary
      const auto w = star.point((i + 1) % star.n_points());
      const std::array<double, 2> mid = {0.5 * (v[0] + w[0]), 0.5 * (v[1] + w[1])};
      CHECK(std::abs(sd(mid)) < 1e-14);
      const std::array<double, 2> in = {0.05 + 0.9 * (v[0] - 0.05), -0.03 + 0.9 * (v[1] + 0.03)};
      CHECK(sd(in) < 0);
    }
  }
  SECTION("points exactly on an axis-aligned polygon give exactly 0") {
    const hg::SignedDistance square(hg::test::rectangle(0, 0, 1, 1, 1.0));
    for (const auto& p : std::vector<std::array<double, 2>>{
             {0.5, 0}, {1, 0.25}, {0.125, 1}, {0, 0.75}, {0, 0}, {1, 1}, {1, 0}, {0, 1}})
      CHECK(square(p) == 0.0);
    CHECK(square(std::array{0.5, 0.5}) == Approx(-0.5));
    CHECK(square(std::array{0.5, 1.25}) == Approx(0.25));
    CHECK(square(std::array{2.0, 0.5}) == Approx(1.0));
    CHECK(square(std::array{0.5, 0.0 + 1e-150}) < 0);  // exact sign 1e-150 away
    CHECK(square(std::array{0.5, 0.0 - 1e-150}) > 0);
  }
}

TEST_CASE("signed distance to a non-convex closed surface matches brute force",
          "[geometry][distance]") {
  const hg::Boundary surface = hg::test::bumpy_surface(3);  // 1280 triangles
  const int n_inside = check_against_brute_force(surface, 2000, 2);
  CHECK(n_inside > 100);
  CHECK(n_inside < 1900);

  const hg::SignedDistance sd(surface);
  CHECK(sd.dim() == 3);
  for (std::int64_t i = 0; i < surface.n_points(); i += 7) {
    const auto v = surface.point(i);
    CHECK(sd(v) == 0.0);
    const std::array<double, 3> in = {0.8 * v[0], 0.8 * v[1], 0.8 * v[2]};
    const std::array<double, 3> out = {1.2 * v[0], 1.2 * v[1], 1.2 * v[2]};
    CHECK(sd(in) < 0);
    CHECK(sd(out) > 0);
  }
  for (std::int64_t f = 0; f < surface.n_facets(); f += 5) {  // edge midpoints, centroids
    const auto t = surface.facet(f);
    const V3 a = point(surface, t[0]), b = point(surface, t[1]), c = point(surface, t[2]);
    const std::array<double, 3> mid = {0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]),
                                       0.5 * (a[2] + b[2])};
    const std::array<double, 3> centroid = {(a[0] + b[0] + c[0]) / 3, (a[1] + b[1] + c[1]) / 3,
                                            (a[2] + b[2] + c[2]) / 3};
    CHECK(std::abs(sd(mid)) < 1e-14);
    CHECK(std::abs(sd(centroid)) < 1e-14);
  }

  SECTION("points exactly on a box (faces, edges, diagonals, corners) give exactly 0") {
    const hg::SignedDistance box(hg::test::box_surface({0, 0, 0}, {1, 2, 4}));
    for (const auto& p : std::vector<std::array<double, 3>>{{0.5, 1, 0},
                                                            {0.5, 0.5, 0},  // face diagonal
                                                            {0, 0, 2},      // box edge
                                                            {1, 2, 4},      // corner
                                                            {0.25, 2, 3},
                                                            {1, 1.5, 0.5}})
      CHECK(box(p) == 0.0);
    CHECK(box(std::array{0.5, 1.0, 2.0}) == Approx(-0.5));
    CHECK(box(std::array{0.5, 1.0, 5.0}) == Approx(1.0));
    CHECK(box(std::array{2.0, 3.0, 4.0}) == Approx(std::sqrt(2.0)));
    CHECK(box(std::array{0.5, 1.0, 1e-150}) < 0);
    CHECK(box(std::array{0.5, 1.0, -1e-150}) > 0);
  }
}

TEST_CASE("distance to a facet subset matches brute force", "[geometry][distance]") {
  for (const hg::Boundary& b : {hg::test::star_polygon(7, 350), hg::test::bumpy_surface(3)}) {
    // A patch (facets with a centroid in x > 0.4) plus every 11th facet elsewhere.
    std::vector<std::int64_t> subset;
    for (std::int64_t f = 0; f < b.n_facets(); ++f) {
      double cx = 0;
      for (const int v : b.facet(f)) cx += b.point(v)[0] / b.dim;
      if (cx > 0.4 || f % 11 == 0) subset.push_back(f);
    }
    REQUIRE(subset.size() < std::size_t(b.n_facets()));
    const hg::FacetSetDistance fd(b, subset);
    CHECK(fd.dim() == b.dim);
    const int n = 2000;
    const std::vector<double> x = random_points(b.dim, n, 3);
    std::vector<double> batched(static_cast<std::size_t>(n));
    fd.evaluate(x, batched);
    for (int i = 0; i < n; ++i) {
      const double* xi = x.data() + i * b.dim;
      const V3 p = {xi[0], xi[1], b.dim == 3 ? xi[2] : 0.0};
      const double expected = brute_distance(b, p, subset);
      CHECK(fd(std::span<const double>(xi, std::size_t(b.dim))) ==
            Approx(expected).margin(1e-12).epsilon(0));
      CHECK(batched[std::size_t(i)] == Approx(expected).margin(1e-12).epsilon(0));
    }
  }
}

TEST_CASE("closest point and side queries match brute force", "[geometry][distance]") {
  for (const hg::Boundary& b : {hg::test::star_polygon(7, 350), hg::test::bumpy_surface(3)}) {
    INFO(b.dim << "D");
    const hg::SignedDistance sd(b);
    const int n = 1500, dim = b.dim;
    const std::vector<double> x = random_points(dim, n, 4);
    std::vector<hg::ClosestPoint> batched(static_cast<std::size_t>(n));
    sd.closest(x, batched);
    const auto facets = all_facets(b);
    for (int i = 0; i < n; ++i) {
      const std::span<const double> xi(x.data() + i * dim, std::size_t(dim));
      const V3 p = {xi[0], xi[1], dim == 3 ? xi[2] : 0.0};
      const hg::ClosestPoint c = sd.closest(xi);
      const double expected = brute_distance(b, p, facets);
      CHECK(c.distance == Approx(expected).margin(1e-12).epsilon(0));
      CHECK(std::abs(sd(xi)) == c.distance);
      // The point is where it says: at that distance from x, on that facet.
      REQUIRE(c.facet >= 0);
      REQUIRE(c.facet < b.n_facets());
      CHECK(norm(sub(p, c.point)) == Approx(c.distance).margin(1e-12).epsilon(0));
      CHECK(brute_distance(b, c.point, {c.facet}) < 1e-12);
      if (dim == 2) CHECK(c.point[2] == 0.0);
      // Batched: the same distance (the facet may differ where two are equally close).
      const hg::ClosestPoint& d = batched[std::size_t(i)];
      CHECK(d.distance == Approx(c.distance).margin(1e-15).epsilon(0));
      CHECK(brute_distance(b, d.point, {d.facet}) < 1e-12);
      // side() is the sign of the signed distance.
      const double s = sd(xi);
      CHECK(sd.side(xi) == (s < 0 ? -1 : s > 0 ? 1 : 0));
    }
  }
  // On the boundary: distance 0, side 0, the point itself.
  const hg::SignedDistance square(hg::test::rectangle(0, 0, 1, 1, 0.5));
  const hg::ClosestPoint c = square.closest(std::array{0.25, 0.0});
  CHECK(c.distance == 0.0);
  CHECK(c.point == V3{0.25, 0.0, 0.0});
  CHECK(c.facet == 0);  // the first segment, (0, 0)-(0.5, 0)
  CHECK(square.side(std::array{0.25, 0.0}) == 0);
  CHECK(square.side(std::array{0.25, 0.5}) == -1);
  CHECK(square.side(std::array{0.25, -1e-300}) == 1);
  const hg::ClosestPoint far = square.closest(std::array{3.0, 4.0});
  CHECK(far.distance == Approx(std::hypot(2.0, 3.0)));
  CHECK(far.point == V3{1.0, 1.0, 0.0});
}

TEST_CASE("distance objects reject bad input and outlive their boundary", "[geometry][distance]") {
  const hg::Boundary star = hg::test::star_polygon(7, 100);
  CHECK_THROWS_AS(hg::FacetSetDistance(star, std::vector<std::int64_t>{}), std::invalid_argument);
  CHECK_THROWS_AS(hg::FacetSetDistance(star, std::vector<std::int64_t>{0, 100}),
                  std::invalid_argument);
  CHECK_THROWS_AS(hg::SignedDistance(hg::Boundary{}), std::invalid_argument);
  hg::Boundary bad = star;
  bad.facets[5] = 1000;
  CHECK_THROWS_AS(hg::SignedDistance(bad), std::invalid_argument);

  std::unique_ptr<hg::SignedDistance> sd;
  {
    const hg::Boundary square = hg::test::rectangle(0, 0, 1, 1, 0.5);
    sd = std::make_unique<hg::SignedDistance>(square);
  }
  hg::SignedDistance moved = std::move(*sd);
  CHECK(moved(std::array{0.5, 0.25}) == Approx(-0.25));
}

// Not run by default (CTest runs it with the slow tests): `unit_tests "[timing]"` prints grid
// evaluation times, wall clock and CPU time of this process (the CPU time is the better number
// on a shared machine); nothing is asserted.
TEST_CASE("signed distance grid timings", "[.][slow][timing]") {
  struct Timer {
    std::chrono::steady_clock::time_point wall = std::chrono::steady_clock::now();
    std::clock_t cpu = std::clock();
    std::string str() const {
      std::ostringstream s;
      s << std::chrono::duration<double>(std::chrono::steady_clock::now() - wall).count()
        << " s (cpu " << double(std::clock() - cpu) / CLOCKS_PER_SEC << " s)";
      return s.str();
    }
  };
  const auto grid = [](int dim, int n) {
    std::vector<double> x;
    std::array<int, 3> i{0, 0, 0};
    for (i[2] = 0; i[2] < (dim == 3 ? n : 1); ++i[2])
      for (i[1] = 0; i[1] < n; ++i[1])
        for (i[0] = 0; i[0] < n; ++i[0])
          for (int k = 0; k < dim; ++k) x.push_back(-1.5 + 3.0 * i[std::size_t(k)] / (n - 1));
    return x;
  };
  const auto run = [&](const hg::Boundary& b, int n, const char* what) {
    const Timer build;
    const hg::SignedDistance sd(b);
    const std::string t_build = build.str();
    const std::vector<double> x = grid(b.dim, n);
    std::vector<double> d(x.size() / std::size_t(b.dim));
    const Timer eval;
    sd.evaluate(x, d);
    std::cout << b.dim << "D: " << b.n_facets() << " " << what << ", build " << t_build << ", " << n
              << "^" << b.dim << " grid " << eval.str() << "\n";
  };
  for (const int n_vertices : {2000, 3000})
    run(hg::test::star_polygon(7, n_vertices), 128, "segments");
  for (const int subdivisions : {5, 6}) run(hg::test::bumpy_surface(subdivisions), 64, "triangles");
}
