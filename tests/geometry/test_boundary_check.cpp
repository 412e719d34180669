/// check_boundary: valid polygons and surfaces pass; each kind of defect is caught with a
/// sentence that names it.
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <numbers>
#include <utility>

#include "geometry/shapes.hpp"
#include "hypershape/geometry/boundary_check.hpp"

using namespace hypershape::geometry;
using Catch::Contains;

// Named for the unity build (HS_UNITY_BUILD): files of one batch share a scope.
namespace test_boundary_check {
namespace {

/// The unit icosphere of tests/geometry/shapes.hpp (20 * 4^level outward triangles), shifted.
Boundary icosphere(int level, std::array<double, 3> shift = {0, 0, 0}) {
  Boundary s = test::icosphere(level);
  for (std::size_t i = 0; i < s.points.size(); ++i) s.points[i] += shift[i % 3];
  return s;
}

/// A star polygon with n tips (2n points), counter-clockwise.
Boundary star(int n_tips) {
  std::vector<double> xy;
  for (int i = 0; i < 2 * n_tips; ++i) {
    const double a = std::numbers::pi * i / n_tips, r = i % 2 ? 0.4 : 1.0;
    xy.insert(xy.end(), {r * std::cos(a), r * std::sin(a)});
  }
  return polygon_boundary(std::move(xy));
}

Boundary merge(const Boundary& a, const Boundary& b) {
  Boundary m = a;
  const int off = int(a.n_points());
  m.points.insert(m.points.end(), b.points.begin(), b.points.end());
  for (int v : b.facets) m.facets.push_back(v + off);
  return m;
}

}  // namespace

TEST_CASE("check_boundary accepts simple counter-clockwise polygons", "[geometry]") {
  const auto r = check_boundary(star(5));
  CHECK(r.ok);
  CHECK(r.reason.empty());
  CHECK(check_boundary(polygon_boundary({0, 0, 1, 0, 0, 1})).ok);
  // Collinear consecutive points are allowed (straight continuation).
  CHECK(check_boundary(polygon_boundary({0, 0, 1, 0, 2, 0, 2, 1})).ok);
}

TEST_CASE("check_boundary rejects bad polygons with the reason", "[geometry]") {
  SECTION("figure eight") {
    const auto r = check_boundary(polygon_boundary({0, 0, 2, 2, 2, 0, 0, 2}));
    CHECK_FALSE(r.ok);
    CHECK_THAT(r.reason, Contains("segments 0 and 2 intersect") && Contains("(1, 1)"));
  }
  SECTION("a vertex touching a non-adjacent segment") {
    const auto r = check_boundary(polygon_boundary({0, 0, 4, 0, 4, 4, 3, 4, 2, 0, 1, 4, 0, 4}));
    CHECK_FALSE(r.ok);
    CHECK_THAT(r.reason, Contains("segments 0 and 3 touch at point 4"));
  }
  SECTION("consecutive segments folding back") {
    const auto r = check_boundary(polygon_boundary({0, 0, 2, 0, 1, 0, 1, 1}));
    CHECK_FALSE(r.ok);
    CHECK_THAT(r.reason, Contains("fold back"));
  }
  SECTION("clockwise") {
    auto b = star(5);
    for (std::size_t f = 0; f < b.facets.size(); f += 2) std::swap(b.facets[f], b.facets[f + 1]);
    const auto r = check_boundary(b);
    CHECK_FALSE(r.ok);
    CHECK_THAT(r.reason, Contains("clockwise polygon"));
  }
  SECTION("repeated point") {
    const auto r = check_boundary(polygon_boundary({0, 0, 1, 0, 1, 0, 1, 1, 0, 1}));
    CHECK_FALSE(r.ok);
    CHECK_THAT(r.reason, Contains("zero-length segment 1") && Contains("repeated point"));
  }
  SECTION("too few points") {
    const auto r = check_boundary(polygon_boundary({0, 0, 1, 0}));
    CHECK_FALSE(r.ok);
    CHECK_THAT(r.reason, Contains("too few segments"));
  }
  SECTION("two loops") {
    const auto r = check_boundary(
        merge(polygon_boundary({0, 0, 1, 0, 0, 1}), polygon_boundary({5, 0, 6, 0, 5, 1})));
    CHECK_FALSE(r.ok);
    CHECK_THAT(r.reason, Contains("more than one closed loop"));
  }
  SECTION("a point used by three segments") {
    Boundary b = polygon_boundary({0, 0, 1, 0, 1, 1, 0, 1});
    b.facets[3] = 0;  // segment 1 now ends at point 0
    const auto r = check_boundary(b);
    CHECK_FALSE(r.ok);
    CHECK_THAT(r.reason, Contains("point 0 is used by 3 segments"));
  }
}

TEST_CASE("check_boundary on a large star polygon", "[geometry]") {
  auto b = star(2500);  // 5000 points
  const auto t0 = std::chrono::steady_clock::now();
  CHECK(check_boundary(b).ok);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  CHECK(seconds < 1.0);  // a sweep, not 12.5M segment pairs
  // Push inner point 1001 out through the far side: its two segments cross others.
  b.points[2 * 1001] *= -3;
  b.points[2 * 1001 + 1] *= -3;
  const auto r = check_boundary(b);
  CHECK_FALSE(r.ok);
  CHECK_THAT(r.reason, Contains("self-intersecting polygon"));
}

TEST_CASE("check_boundary accepts an icosphere", "[geometry]") {
  for (int level : {0, 1, 3}) {
    const auto r = check_boundary(icosphere(level));
    INFO(r.reason);
    CHECK(r.ok);
  }
}

TEST_CASE("check_boundary rejects bad surfaces with the reason", "[geometry]") {
  SECTION("one triangle removed") {
    auto s = icosphere(2);
    s.facets.resize(s.facets.size() - 3);
    const auto r = check_boundary(s);
    CHECK_FALSE(r.ok);
    CHECK_THAT(r.reason, Contains("open surface: 3 boundary edges"));
  }
  SECTION("one triangle flipped") {
    auto s = icosphere(2);
    std::swap(s.facets[3 * 17 + 1], s.facets[3 * 17 + 2]);
    const auto r = check_boundary(s);
    CHECK_FALSE(r.ok);
    CHECK_THAT(r.reason, Contains("inconsistent orientation") && Contains("triangles"));
  }
  SECTION("all triangles flipped") {
    auto s = icosphere(1);
    for (std::size_t f = 0; f < s.facets.size(); f += 3)
      std::swap(s.facets[f + 1], s.facets[f + 2]);
    const auto r = check_boundary(s);
    CHECK_FALSE(r.ok);
    CHECK_THAT(r.reason, Contains("inward orientation") && Contains("-"));
  }
  SECTION("two overlapping icospheres") {
    const auto r = check_boundary(merge(icosphere(2), icosphere(2, {0.5, 0, 0})));
    CHECK_FALSE(r.ok);
    CHECK_THAT(r.reason, Contains("2 connected components (320, 320 triangles)"));
  }
  SECTION("a vertex pushed through the far side") {
    auto s = icosphere(2);
    for (int k = 0; k < 3; ++k) s.points[k] *= -1.5;  // point 0 goes to the other side
    const auto r = check_boundary(s);
    CHECK_FALSE(r.ok);
    CHECK_THAT(r.reason, Contains("self-intersecting surface: triangles"));
  }
  SECTION("two tetrahedra sharing one edge") {
    Boundary s;
    s.dim = 3;
    // Edge 0-1 on the z axis; tetrahedron A towards +x, B towards -x.
    s.points = {0, 0, 0, 0, 0, 1, 1, 0, 0.5, 2, 1, 0.5, -1, 0, 0.5, -2, -1, 0.5};
    auto tet = [&](int a, int b, int c, int d) {  // outward for a positively oriented tet
      s.facets.insert(s.facets.end(), {a, c, b, a, b, d, a, d, c, b, c, d});
    };
    tet(0, 1, 2, 3);
    tet(0, 1, 4, 5);
    const auto r = check_boundary(s);
    CHECK_FALSE(r.ok);
    CHECK_THAT(r.reason, Contains("non-manifold edge: points 0 and 1 are shared by 4 triangles"));
  }
  SECTION("two tetrahedra sharing one vertex") {
    Boundary s;
    s.dim = 3;
    s.points = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, -1, 0, 0, 0, -1, 0, 0, 0, -1};
    auto tet = [&](int a, int b, int c, int d) {
      s.facets.insert(s.facets.end(), {a, c, b, a, b, d, a, d, c, b, c, d});
    };
    tet(0, 1, 2, 3);
    tet(0, 4, 6, 5);
    // Orient both outward whatever the handedness of the corner: flip a tet if its volume < 0.
    for (int t = 0; t < 2; ++t) {
      double v6 = 0;
      for (int f = 4 * t; f < 4 * t + 4; ++f) {
        const double* a = &s.points[3 * s.facets[3 * f]];
        const double* b = &s.points[3 * s.facets[3 * f + 1]];
        const double* c = &s.points[3 * s.facets[3 * f + 2]];
        v6 += a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
              a[2] * (b[0] * c[1] - b[1] * c[0]);
      }
      if (v6 < 0)
        for (int f = 4 * t; f < 4 * t + 4; ++f) std::swap(s.facets[3 * f + 1], s.facets[3 * f + 2]);
    }
    const auto r = check_boundary(s);
    CHECK_FALSE(r.ok);
    CHECK_THAT(r.reason, Contains("non-manifold vertex") && Contains("point 0") &&
                             Contains("2 separate fans"));
  }
  SECTION("degenerate triangle") {
    auto s = icosphere(1);
    s.facets[3 * 5 + 2] = s.facets[3 * 5];
    const auto r = check_boundary(s);
    CHECK_FALSE(r.ok);
    CHECK_THAT(r.reason, Contains("degenerate triangle 5"));
  }
  SECTION("an index out of range") {
    auto s = icosphere(1);
    s.facets[7] = 1000;
    const auto r = check_boundary(s);
    CHECK_FALSE(r.ok);
    CHECK_THAT(r.reason, Contains("triangle 2 refers to point 1000"));
  }
}

TEST_CASE("check_boundary on 82k triangles is fast", "[geometry]") {
  const auto s = icosphere(6);  // 81920 triangles
  const auto t0 = std::chrono::steady_clock::now();
  const auto r = check_boundary(s);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  INFO(r.reason);
  CHECK(r.ok);
  CHECK(seconds < 2.0);
}

}  // namespace test_boundary_check
