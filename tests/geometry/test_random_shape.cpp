// Random deformations of the sphere: the pre-image refinement of the deformed surface ends, keeps
// a closed oriented 2-manifold whose image edges are all resolved, and is a pure function of the
// random stream; the per-dimension velocity unit.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>
#include <vector>

#include "hypershape/core/random.hpp"
#include "hypershape/geometry/random_shape.hpp"

using namespace hypershape;

namespace {

/// Longest edge of the surface.
double longest_edge(const geometry::Boundary& b) {
  double longest = 0.0;
  for (std::int64_t f = 0; f < b.n_facets(); ++f) {
    const auto v = b.facet(f);
    for (int q = 0; q < 3; ++q) {
      const auto p = b.point(v[q]), r = b.point(v[(q + 1) % 3]);
      longest = std::max(longest, std::hypot(p[0] - r[0], p[1] - r[1], p[2] - r[2]));
    }
  }
  return longest;
}

/// Every directed edge once and its reverse once (closed, consistently oriented 2-manifold
/// triangulation) and Euler characteristic 2 (a sphere). Says nothing about self-intersections.
void require_oriented_sphere(const geometry::Boundary& b) {
  std::map<std::pair<int, int>, int> directed;
  for (std::int64_t f = 0; f < b.n_facets(); ++f) {
    const auto v = b.facet(f);
    for (int q = 0; q < 3; ++q) ++directed[{v[q], v[(q + 1) % 3]}];
  }
  for (const auto& [e, count] : directed) {
    REQUIRE(count == 1);
    REQUIRE(directed.count({e.second, e.first}) == 1);
  }
  const std::int64_t n_edges = std::int64_t(directed.size()) / 2;
  CHECK(b.n_points() - n_edges + b.n_facets() == 2);
}

geometry::DeformationSpec random3d_spec(double velocity_unit) {
  geometry::DeformationSpec spec;
  spec.dim = 3;
  spec.steps = {{0.2, 4.0}, {0.1, 4.0}, {0.05, 1.0}};  // Random3D, the paper's Table 1
  spec.velocity_unit = velocity_unit;
  return spec;
}

}  // namespace

TEST_CASE("per-dimension velocity unit", "[geometry][random_shape]") {
  CHECK(geometry::default_velocity_unit(2) == 0.04);
  CHECK(geometry::default_velocity_unit(3) < geometry::default_velocity_unit(2));
  // An unset unit (NaN) is the default of the dimension: the same deformation as setting it.
  geometry::DeformationSpec unset = random3d_spec(std::nan(""));
  geometry::DeformationSpec set = random3d_spec(geometry::default_velocity_unit(3));
  unset.steps = set.steps = {{0.3, 2.0}};
  const std::vector<double> base = geometry::icosphere(2).points;
  core::RandomStream r1(5, core::Purpose::test, {1}), r2(5, core::Purpose::test, {1});
  const auto a = geometry::sample_deformation(unset, base, r1);
  const auto b = geometry::sample_deformation(set, base, r2);
  double x[3] = {0.3, -0.2, 0.5}, y[3] = {0.3, -0.2, 0.5};
  a.map(x);
  b.map(y);
  CHECK(x[0] == y[0]);
  CHECK(x[1] == y[1]);
  CHECK(x[2] == y[2]);
  unset.velocity_unit = -1.0;
  core::RandomStream r3(5, core::Purpose::test, {1});
  CHECK_THROWS_AS(geometry::sample_deformation(unset, base, r3), std::invalid_argument);
}

TEST_CASE("the identity map refines the icosphere to the spacing", "[geometry][random_shape]") {
  geometry::DeformationSpec spec = random3d_spec(0.0);  // m * 0: v = 0
  spec.steps = {{0.3, 1.0}};
  const geometry::Boundary base = geometry::icosphere(1);
  core::RandomStream rng(1, core::Purpose::test, {0});
  geometry::RandomDeformation phi = geometry::sample_deformation(spec, base.points, rng);
  const double spacing = 0.15;
  const geometry::SurfaceSamples s =
      geometry::sample_surface_image(phi, base, geometry::BaseKind::sphere, spacing);
  require_oriented_sphere(s.surface);
  CHECK(longest_edge(s.surface) <= spacing * (1 + 1e-12));
  // Longest-edge bisection of a near-equilateral base: edges stay within a factor of about 2.
  CHECK(longest_edge(s.surface) > 0.4 * spacing);
  // Pre-images on the unit sphere; images are the sphere fitted into [-1, 1]^3.
  double lo = 1e300, hi = -1e300;
  for (std::int64_t i = 0; i < s.surface.n_points(); ++i) {
    const double* p = &s.preimage[3 * std::size_t(i)];
    REQUIRE(std::hypot(p[0], p[1], p[2]) == Approx(1.0).epsilon(1e-14));
    for (int a = 0; a < 3; ++a) lo = std::min(lo, s.surface.point(i)[a]), hi = std::max(hi, s.surface.point(i)[a]);
  }
  CHECK(lo == Approx(-1.0).epsilon(1e-12));
  CHECK(hi == Approx(1.0).epsilon(1e-12));
}

TEST_CASE("the pre-image refinement ends on wild draws", "[geometry][random_shape]") {
  // At twice the 3D default velocity unit the Random3D flows fold the sphere back on itself
  // closer than the spacing. The former refinement (split the longest IMAGE edge) piled points on
  // a pre-image edge whose image stays short (measured at unit 0.02: 6 draws of 6 passed 300k
  // points); longest-edge bisection in the pre-image resolves such draws with about 40k points.
  const geometry::Boundary base = geometry::icosphere(3);
  const double spacing = 0.1;
  core::RandomStream rng(1005, core::Purpose::test, {0});
  geometry::RandomDeformation phi =
      geometry::sample_deformation(random3d_spec(0.025), geometry::icosphere(4).points, rng);
  // Too few points allowed: a clear error, not a hang (phi is left as it was).
  CHECK_THROWS_AS(geometry::sample_surface_image(phi, base, geometry::BaseKind::sphere, spacing, 2000),
                  std::runtime_error);
  const geometry::SurfaceSamples s =
      geometry::sample_surface_image(phi, base, geometry::BaseKind::sphere, spacing, 200'000);
  require_oriented_sphere(s.surface);
  CHECK(longest_edge(s.surface) <= spacing * (1 + 1e-9));
  // Every point is the image of its pre-image.
  for (std::int64_t i = 0; i < s.surface.n_points(); i += 97) {
    double x[3] = {s.preimage[3 * i], s.preimage[3 * i + 1], s.preimage[3 * i + 2]};
    phi.map(x);
    for (int a = 0; a < 3; ++a) REQUIRE(x[a] == s.surface.point(i)[a]);
  }
}
