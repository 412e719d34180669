// Shape metrics against closed forms: measures, isoperimetric ratio, Hausdorff distances with a
// known answer, and medial-ball radii of circles, spheres and thin strips.
#include <algorithm>
#include <array>
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <iostream>
#include <numbers>
#include <stdexcept>
#include <vector>

#include "geometry/shapes.hpp"
#include "hypershape/geometry/metrics.hpp"

namespace hg = hypershape::geometry;
using std::numbers::pi;

namespace {

double min_of(const std::vector<double>& v) { return *std::min_element(v.begin(), v.end()); }
double max_of(const std::vector<double>& v) { return *std::max_element(v.begin(), v.end()); }

}  // namespace

TEST_CASE("enclosed and boundary measures", "[geometry][metrics]") {
  const hg::Boundary square = hg::test::rectangle(0, 0, 1, 1, 0.3);
  CHECK(hg::enclosed_measure(square) == Approx(1.0).epsilon(1e-15));
  CHECK(hg::boundary_measure(square) == Approx(4.0).epsilon(1e-15));
  CHECK(hg::enclosed_measure(hg::test::rectangle(-3, 1, 2, 1.5, 1.0)) == Approx(2.5));

  const hg::Boundary hexagon = hg::test::regular_polygon(6, 2.0, 0.3);
  CHECK(hg::enclosed_measure(hexagon) == Approx(1.5 * std::sqrt(3.0) * 4));
  CHECK(hg::boundary_measure(hexagon) == Approx(12.0));
  hg::Boundary clockwise = hexagon;  // reversed orientation: negative area
  for (std::size_t i = 0; i < clockwise.facets.size(); i += 2)
    std::swap(clockwise.facets[i], clockwise.facets[i + 1]);
  CHECK(hg::enclosed_measure(clockwise) == Approx(-1.5 * std::sqrt(3.0) * 4));

  const hg::Boundary box = hg::test::box_surface({-1, 0, 2}, {1, 3, 6});
  CHECK(hg::enclosed_measure(box) == Approx(2.0 * 3 * 4));
  CHECK(hg::boundary_measure(box) == Approx(2 * (2.0 * 3 + 3.0 * 4 + 2.0 * 4)));

  hg::Boundary tetrahedron;
  tetrahedron.dim = 3;
  tetrahedron.points = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  tetrahedron.facets = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
  CHECK(hg::enclosed_measure(tetrahedron) == Approx(1.0 / 6));
  CHECK(hg::boundary_measure(tetrahedron) == Approx(1.5 + std::sqrt(3.0) / 2));

  // An icosphere converges to the unit ball from inside.
  const double v3 = hg::enclosed_measure(hg::test::icosphere(3));
  const double v4 = hg::enclosed_measure(hg::test::icosphere(4));
  CHECK(v3 < v4);
  CHECK(v4 < 4 * pi / 3);
  CHECK(v4 == Approx(4 * pi / 3).epsilon(3e-3));
  CHECK(hg::boundary_measure(hg::test::icosphere(4)) == Approx(4 * pi).epsilon(3e-3));

  CHECK_THROWS_AS(hg::enclosed_measure(hg::Boundary{}), std::invalid_argument);
}

TEST_CASE("isoperimetric ratio", "[geometry][metrics]") {
  CHECK(std::abs(hg::isoperimetric_ratio(hg::test::rectangle(0, 0, 1, 1, 1.0)) - pi / 4) < 1e-15);
  for (const int n : {3, 4, 7, 50, 1000}) {
    INFO("n = " << n);
    const double expected = (pi / n) / std::tan(pi / n);
    CHECK(hg::isoperimetric_ratio(hg::test::regular_polygon(n, 1.7, 0.1)) ==
          Approx(expected).epsilon(1e-12));
  }
  CHECK(hg::isoperimetric_ratio(hg::test::regular_polygon(1000, 1.0)) > 0.99999);
  CHECK(hg::isoperimetric_ratio(hg::test::star_polygon(7, 300)) < 0.8);
  // 3D: 36 pi V^2 / S^3, 1 for a ball (a fine icosphere is close), finite (it was NaN in shards).
  CHECK(hg::isoperimetric_ratio(hg::test::icosphere(4)) > 0.99);
  CHECK(hg::isoperimetric_ratio(hg::test::icosphere(4)) <= 1.0);
}

TEST_CASE("Hausdorff distance", "[geometry][metrics]") {
  SECTION("of a boundary with itself is 0") {
    const hg::Boundary star = hg::test::star_polygon(7, 300);
    CHECK(hg::hausdorff_distance(star, star, 1e-6) < 1e-15);  // round-off at facet midpoints
    const hg::Boundary bumpy = hg::test::bumpy_surface(2);
    CHECK(hg::hausdorff_distance(bumpy, bumpy, 1e-6) < 1e-15);
  }
  SECTION("asymmetric, attained inside facets: [0,1]^2 vs [0,2]x[0,1]") {
    // Every vertex of A lies on B: the 0.5 of A -> B is attained at (1, 0.5), mid-facet.
    const hg::Boundary a = hg::test::rectangle(0, 0, 1, 1, 1.0);
    const hg::Boundary b = hg::test::rectangle(0, 0, 2, 1, 2.0);
    for (const double tol : {1e-2, 1e-6}) {
      const double ab = hg::directed_hausdorff_distance(a, b, tol);
      const double ba = hg::directed_hausdorff_distance(b, a, tol);
      CHECK(ab <= 0.5 + 1e-15);
      CHECK(ab >= 0.5 - tol);
      CHECK(ba == Approx(1.0).epsilon(1e-15));
      CHECK(hg::hausdorff_distance(a, b, tol) == Approx(1.0).epsilon(1e-15));
      CHECK(hg::hausdorff_distance(b, a, tol) == Approx(1.0).epsilon(1e-15));
    }
  }
  SECTION("square vs its circumscribed circle: sqrt(2) - 1 at the edge midpoints") {
    const hg::Boundary square = hg::test::rectangle(-1, -1, 1, 1, 2.0);  // corners only
    const hg::Boundary circle = hg::test::regular_polygon(4000, std::sqrt(2.0), pi / 4);
    const double tol = 1e-4;
    const double h = hg::directed_hausdorff_distance(square, circle, tol);
    CHECK(h <= std::sqrt(2.0) - 1 + 1e-12);
    CHECK(h >= std::sqrt(2.0) - 1 - tol - 1e-6);  // 1e-6: the 4000-gon is inside the circle
  }
  SECTION("sphere vs the sphere scaled by 1.1: 0.1 up to the discretisation") {
    const hg::Boundary sphere = hg::test::icosphere(3);
    const hg::Boundary larger = hg::test::scaled(sphere, 1.1);
    const auto t0 = std::chrono::steady_clock::now();
    const double tol = 1e-3;
    const double h = hg::hausdorff_distance(sphere, larger, tol);
    std::cout << "Hausdorff icosphere(3) vs 1.1x (" << sphere.n_facets() << " triangles each, tol "
              << tol << "): " << h << " in "
              << std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count()
              << " s\n";
    // Vertices are at distance 0.1; the facets sag by at most 1 - cos(edge/2) < 0.01.
    CHECK(h >= 0.1);
    CHECK(h <= 0.11);
    CHECK(hg::hausdorff_distance(sphere, hg::test::scaled(sphere, 1.5), tol) >= 0.5);
  }
  CHECK_THROWS_AS(
      hg::hausdorff_distance(hg::test::icosphere(0), hg::test::regular_polygon(5, 1), 0.1),
      std::invalid_argument);
  CHECK_THROWS_AS(hg::hausdorff_distance(hg::test::icosphere(0), hg::test::icosphere(0), 0.0),
                  std::invalid_argument);
}

TEST_CASE("inscribed and exterior radii", "[geometry][metrics]") {
  SECTION("circle: R everywhere inside, the cap outside") {
    const double radius = 0.7;
    const hg::Boundary circle = hg::test::regular_polygon(400, radius, 0.1);
    const auto r = hg::inscribed_radii(circle);
    REQUIRE(r.size() == 400);
    CHECK(min_of(r) == Approx(radius).epsilon(0.01));
    CHECK(max_of(r) == Approx(radius).epsilon(0.01));
    const auto e = hg::exterior_radii(circle);
    CHECK(min_of(e) == Approx(2 * std::sqrt(2.0) * radius).epsilon(0.01));  // bbox diagonal
  }
  SECTION("thin 2 x 0.1 strip: w/2 on the long sides, the bisector ball at the corners") {
    const double h = GENERATE(0.5, 0.01);  // coarse (few long facets) and fine sampling
    INFO("facet length " << h);
    const hg::Boundary strip = hg::test::rectangle(-1, -0.05, 1, 0.05, h);
    const auto r = hg::inscribed_radii(strip);
    const double corner = 0.1 / (1 + std::sqrt(0.5));  // centre on the bisector, touches y = w
    int n_long = 0, n_corners = 0;
    for (std::int64_t i = 0; i < strip.n_points(); ++i) {
      const auto p = strip.point(i);
      INFO("point (" << p[0] << ", " << p[1] << ")");
      const bool on_long_side = std::abs(std::abs(p[1]) - 0.05) < 1e-12;
      if (on_long_side && std::abs(p[0]) < 0.7) {
        CHECK(r[std::size_t(i)] == Approx(0.05).epsilon(1e-9));
        ++n_long;
      }
      if (on_long_side && std::abs(std::abs(p[0]) - 1) < 1e-12) {
        // Up to the sagitta of the far side's facets where they count as samples (h <= r/2).
        CHECK(r[std::size_t(i)] == Approx(corner).epsilon(1e-3));
        ++n_corners;
      }
      // Everywhere: positive, at most the corner ball, and on the short sides at least the
      // distance to the nearest corner (the exact medial ball there).
      CHECK(r[std::size_t(i)] > 0);
      CHECK(r[std::size_t(i)] <= corner * (1 + 1e-3));
      if (!on_long_side) CHECK(r[std::size_t(i)] >= (0.05 - std::abs(p[1])) * (1 - 1e-9));
    }
    CHECK(n_long >= 3);
    CHECK(n_corners == 4);
  }
  SECTION("ellipse: curvature radius b^2/a at the tips, b at the ends of the minor axis") {
    std::vector<double> xy;
    const int n = 400;
    for (int i = 0; i < n; ++i)
      xy.insert(xy.end(), {std::cos(2 * pi * i / n), 0.5 * std::sin(2 * pi * i / n)});
    const auto r = hg::inscribed_radii(hg::polygon_boundary(xy));
    CHECK(r[0] == Approx(0.25).epsilon(1e-3));
    CHECK(r[n / 2] == Approx(0.25).epsilon(1e-3));
    CHECK(r[n / 4] == Approx(0.5).epsilon(1e-12));
    CHECK(min_of(r) == Approx(0.25).epsilon(1e-3));
    CHECK(max_of(r) == Approx(0.5).epsilon(1e-12));
  }
  SECTION("box: the diagonal ball at the corners, half the thickness on the faces") {
    // 12 triangles: the corner balls meet the far faces, which are long facets taken literally.
    const auto r = hg::inscribed_radii(hg::test::box_surface({0, 0, 0}, {1, 1, 1}));
    for (const double x : r) CHECK(x == Approx(1 / (1 + 1 / std::sqrt(3.0))).epsilon(1e-8));
    const hg::Boundary slab = hg::test::box_surface({0, 0, 0}, {4, 4, 0.2});
    const auto s = hg::inscribed_radii(slab);
    // Corner ball: centre on the diagonal, touches z = 0.2 first.
    for (const double x : s) CHECK(x == Approx(0.2 / (1 + 1 / std::sqrt(3.0))).epsilon(1e-8));
  }
  SECTION("two arms separated by a narrow slot") {
    // A U: two 0.4-wide arms joined at the bottom; the slot between them is 0.06 wide.
    const std::vector<double> xy = {0,    0,   0.86, 0,   0.86, 1, 0.46, 1,
                                    0.46, 0.3, 0.4,  0.3, 0.4,  1, 0,    1};
    std::vector<double> fine;  // split the sides into pieces of <= 0.02
    for (std::size_t i = 0; i < xy.size(); i += 2) {
      const double x0 = xy[i], y0 = xy[i + 1], x1 = xy[(i + 2) % xy.size()],
                   y1 = xy[(i + 3) % xy.size()];
      const int m = std::max(1, int(std::ceil(std::hypot(x1 - x0, y1 - y0) / 0.02 - 1e-9)));
      for (int k = 0; k < m; ++k)
        fine.insert(fine.end(), {x0 + (x1 - x0) * k / m, y0 + (y1 - y0) * k / m});
    }
    const hg::Boundary u = hg::polygon_boundary(fine);
    const auto inner = hg::inscribed_radii(u);
    const auto outer = hg::exterior_radii(u);
    int n_slot = 0, n_arm = 0;
    for (std::int64_t i = 0; i < u.n_points(); ++i) {
      const auto p = u.point(i);
      INFO("point (" << p[0] << ", " << p[1] << ")");
      const bool slot_wall = (std::abs(p[0] - 0.4) < 1e-12 || std::abs(p[0] - 0.46) < 1e-12);
      if (slot_wall && p[1] > 0.35 && p[1] < 0.78) {
        CHECK(outer[std::size_t(i)] == Approx(0.03).epsilon(1e-9));  // half the slot width
        CHECK(inner[std::size_t(i)] == Approx(0.2).epsilon(1e-9));   // half the arm width
        ++n_slot;
      }
      const bool outer_wall = std::abs(p[0]) < 1e-12 || std::abs(p[0] - 0.86) < 1e-12;
      if (outer_wall && p[1] > 0.45 && p[1] < 0.75) {
        CHECK(inner[std::size_t(i)] == Approx(0.2).epsilon(1e-9));
        CHECK(outer[std::size_t(i)] == Approx(std::hypot(0.86, 1.0)).epsilon(1e-12));  // cap
        ++n_arm;
      }
    }
    CHECK(n_slot > 30);
    CHECK(n_arm > 20);
    const auto metrics = hg::compute_metrics(u, nullptr, 1e-3);
    CHECK(metrics.min_exterior_gap == min_of(outer));
    CHECK(metrics.min_local_feature_size == min_of(inner));
    CHECK(metrics.min_exterior_gap <= 0.03 * (1 + 1e-9));
    CHECK(metrics.measure == Approx(0.86 - 0.06 * 0.7));
    CHECK(std::isnan(metrics.hausdorff_to_base));
    CHECK(metrics.n_boundary_facets == u.n_facets());
  }
  SECTION("sphere: R inside, the cap outside; ellipsoid: c^2/a at the tip") {
    const hg::Boundary sphere = hg::test::scaled(hg::test::icosphere(3), 2.0);
    const auto r = hg::inscribed_radii(sphere);
    CHECK(min_of(r) == Approx(2.0).epsilon(1e-9));  // vertices on the sphere: exact
    CHECK(max_of(r) == Approx(2.0).epsilon(1e-9));
    const auto e = hg::exterior_radii(sphere);
    CHECK(min_of(e) ==
          Approx(4 * std::sqrt(3.0)).epsilon(1e-12));  // convex: the cap, bbox diagonal

    hg::Boundary ellipsoid = hg::test::icosphere(4);  // semi-axes 1, 0.8, 0.5
    for (std::size_t i = 0; i < ellipsoid.points.size(); i += 3) {
      ellipsoid.points[i + 1] *= 0.8;
      ellipsoid.points[i + 2] *= 0.5;
    }
    const auto re = hg::inscribed_radii(ellipsoid);
    for (std::int64_t i = 0; i < ellipsoid.n_points(); ++i) {
      const auto p = ellipsoid.point(i);
      if (std::abs(p[0]) > 1 - 1e-12) CHECK(re[std::size_t(i)] == Approx(0.25).epsilon(0.01));
      if (std::abs(p[2]) > 0.5 - 1e-12) CHECK(re[std::size_t(i)] == Approx(0.5).epsilon(1e-9));
    }
    CHECK(min_of(re) == Approx(0.25).epsilon(0.01));
  }
}

TEST_CASE("compute_metrics", "[geometry][metrics]") {
  const hg::Boundary base = hg::test::icosphere(2);
  const hg::Boundary shape = hg::test::bumpy_surface(2);
  const auto m = hg::compute_metrics(shape, &base, 1e-3);
  CHECK(m.measure == Approx(hg::enclosed_measure(shape)));
  CHECK(m.boundary_measure == Approx(hg::boundary_measure(shape)));
  CHECK(m.isoperimetric_ratio == Approx(hg::isoperimetric_ratio(shape)));  // 3D: 36 pi V^2 / S^3, finite
  CHECK(m.isoperimetric_ratio > 0);
  CHECK(m.isoperimetric_ratio < 1);
  CHECK(m.hausdorff_to_base == Approx(hg::hausdorff_distance(shape, base, 1e-3)).margin(1e-3));
  CHECK(m.hausdorff_to_base > 0.1);
  CHECK(m.n_boundary_facets == 320);
  CHECK(m.min_local_feature_size > 0.05);
  CHECK(m.min_local_feature_size < 1.0);
  CHECK(m.min_exterior_gap > 0);

  const hg::Boundary disk = hg::test::regular_polygon(200, 1.0);
  const auto d = hg::compute_metrics(disk, &disk, 1e-3);
  CHECK(d.isoperimetric_ratio == Approx(hg::isoperimetric_ratio(disk)));
  CHECK(d.hausdorff_to_base < 1e-15);
  CHECK(d.min_local_feature_size == Approx(1.0).epsilon(0.01));
}
