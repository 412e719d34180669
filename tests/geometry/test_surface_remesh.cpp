/// remesh_surface: isotropic remeshing stays on the input surface with edges near the target;
/// with a clamp sphere the patch boundary is drawn into the mesh with its vertices exactly on the
/// sphere, and facets_in_ball picks the patch whose area matches the spherical cap.
#include <algorithm>
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <map>
#include <numbers>
#include <set>
#include <stdexcept>

#include "geometry/shapes.hpp"
#include "hypershape/geometry/boundary_check.hpp"
#include "hypershape/geometry/surface_remesh.hpp"

using namespace hypershape::geometry;

namespace {

double dist(std::span<const double> x, const std::array<double, 3>& c) {
  return std::sqrt((x[0] - c[0]) * (x[0] - c[0]) + (x[1] - c[1]) * (x[1] - c[1]) +
                   (x[2] - c[2]) * (x[2] - c[2]));
}

double triangle_area(const Boundary& b, std::int64_t f) {
  const auto t = b.facet(f);
  const auto p = b.point(t[0]), q = b.point(t[1]), r = b.point(t[2]);
  const double u[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]};
  const double v[3] = {r[0] - p[0], r[1] - p[1], r[2] - p[2]};
  const double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                       u[0] * v[1] - u[1] * v[0]};
  return 0.5 * std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
}

/// Smallest angle of triangle f, in degrees.
double min_angle(const Boundary& b, std::int64_t f) {
  const auto t = b.facet(f);
  double m = 180;
  for (int k = 0; k < 3; ++k) {
    const auto p = b.point(t[k]), q = b.point(t[(k + 1) % 3]), r = b.point(t[(k + 2) % 3]);
    double u[3], v[3], uv = 0, uu = 0, vv = 0;
    for (int i = 0; i < 3; ++i) {
      u[i] = q[i] - p[i];
      v[i] = r[i] - p[i];
      uv += u[i] * v[i];
      uu += u[i] * u[i];
      vv += v[i] * v[i];
    }
    m = std::min(
        m, std::acos(std::clamp(uv / std::sqrt(uu * vv), -1.0, 1.0)) * 180 / std::numbers::pi);
  }
  return m;
}

std::vector<double> edge_lengths(const Boundary& b) {
  std::set<std::pair<int, int>> edges;
  for (std::int64_t f = 0; f < b.n_facets(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = b.facet(f)[k], c = b.facet(f)[(k + 1) % 3];
      edges.insert(std::minmax(a, c));
    }
  std::vector<double> len;
  for (auto [a, c] : edges) {
    const auto p = b.point(a), q = b.point(c);
    len.push_back(std::hypot(p[0] - q[0], p[1] - q[1], p[2] - q[2]));
  }
  return len;
}

double volume(const Boundary& b) {
  double v6 = 0;
  for (std::int64_t f = 0; f < b.n_facets(); ++f) {
    const auto t = b.facet(f);
    const auto a = b.point(t[0]), c = b.point(t[1]), d = b.point(t[2]);
    v6 += a[0] * (c[1] * d[2] - c[2] * d[1]) - a[1] * (c[0] * d[2] - c[2] * d[0]) +
          a[2] * (c[0] * d[1] - c[1] * d[0]);
  }
  return v6 / 6;
}

}  // namespace

TEST_CASE("remesh_surface makes near-equilateral triangles of the target size on the input",
          "[geometry]") {
  const Boundary in = test::icosphere(2);  // 320 triangles, edges about 0.3
  RemeshOptions opt;
  opt.target_edge = 0.1;
  const Boundary out = remesh_surface(in, opt);
  const auto check = check_boundary(out);
  INFO(check.reason);
  REQUIRE(check.ok);
  CHECK(out.n_facets() > 2000);  // area 4 pi / (0.1^2 sqrt(3)/4) = 2900 equilateral triangles
  CHECK(out.n_facets() < 4000);

  const auto len = edge_lengths(out);
  const auto in_range = std::count_if(len.begin(), len.end(), [&](double l) {
    return l >= 0.6 * opt.target_edge && l <= 1.5 * opt.target_edge;
  });
  CHECK(double(in_range) / double(len.size()) > 0.97);
  int n_poor = 0;
  for (std::int64_t f = 0; f < out.n_facets(); ++f) n_poor += min_angle(out, f) < 30;
  CHECK(double(n_poor) / double(out.n_facets()) < 0.03);

  // On the input surface: the level-2 icosphere is within 0.015 of the unit sphere (its
  // vertices are on it) and encloses the same volume to round-off.
  for (std::int64_t i = 0; i < out.n_points(); ++i) {
    const double r = dist(out.point(i), {0, 0, 0});
    CHECK(r <= 1 + 1e-12);
    CHECK(r >= 1 - 0.02);
  }
  CHECK(volume(out) == Approx(volume(in)).epsilon(0.01));
}

TEST_CASE("remesh_surface draws the clamp curve with its vertices on the sphere", "[geometry]") {
  const std::array<double, 3> c = {0, 0, 1};
  const double r = 0.5;
  const int level = GENERATE(2, 4);  // coarser and finer than the target
  INFO("icosphere level " << level);
  const Boundary in = test::icosphere(level);
  RemeshOptions opt;
  opt.target_edge = 0.1;
  opt.clamp_center = c;
  opt.clamp_radius = r;
  const Boundary out = remesh_surface(in, opt);
  const auto check = check_boundary(out);
  INFO(check.reason);
  REQUIRE(check.ok);

  // The patch and its boundary edges (one patch facet, one other).
  const auto patch = facets_in_ball(out, c, r);
  REQUIRE(!patch.empty());
  std::vector<char> in_patch(std::size_t(out.n_facets()), 0);
  for (int f : patch) in_patch[std::size_t(f)] = 1;
  std::map<std::pair<int, int>, int> edge_count;  // patch facets per undirected edge
  std::map<std::pair<int, int>, int> edge_total;
  for (std::int64_t f = 0; f < out.n_facets(); ++f)
    for (int k = 0; k < 3; ++k) {
      const auto e = std::minmax(out.facet(f)[k], out.facet(f)[(k + 1) % 3]);
      edge_total[e]++;
      edge_count[e] += in_patch[std::size_t(f)];
    }
  std::map<int, int> curve_degree;
  for (auto& [e, n] : edge_count)
    if (n == 1) {
      curve_degree[e.first]++;
      curve_degree[e.second]++;
    }
  // One closed curve of about 2 pi 0.484 / 0.1 = 30 vertices, all on the sphere to round-off.
  CHECK(curve_degree.size() >= 20);
  CHECK(curve_degree.size() <= 45);
  double max_off = 0;
  for (auto [v, deg] : curve_degree) {
    CHECK(deg == 2);
    max_off = std::max(max_off, std::abs(dist(out.point(v), c) - r));
    // The circle z = 7/8, less the faceting of the input (0.015 / 0.001 at levels 2 / 4).
    CHECK(std::abs(out.point(v)[2] - 0.875) < (level == 2 ? 0.02 : 0.002));
  }
  CHECK(max_off <= 1e-12);
  // Every other facet has a vertex strictly outside (the patch is exactly the facet test).
  for (std::int64_t f = 0; f < out.n_facets(); ++f) {
    if (in_patch[std::size_t(f)]) continue;
    double dmax = 0;
    for (int v : out.facet(f)) dmax = std::max(dmax, dist(out.point(v), c));
    CHECK(dmax > r * (1 + 1e-9));
  }

  // Patch area vs the spherical cap 2 pi R h, h = 1 - 7/8, less the faceting of the input.
  double area = 0, total = 0;
  for (int f : patch) area += triangle_area(out, f);
  for (std::int64_t f = 0; f < out.n_facets(); ++f) total += triangle_area(out, f);
  const double cap = 2 * std::numbers::pi * 1.0 * 0.125;
  const double faceting = total / (4 * std::numbers::pi);  // area ratio of the faceted sphere
  INFO("patch area " << area << ", cap " << cap << ", faceting ratio " << faceting);
  CHECK(area == Approx(cap * faceting).epsilon(0.01));
  CHECK(area == Approx(cap).epsilon(level == 2 ? 0.05 : 0.02));
}

TEST_CASE("remesh_surface refines locally, on the input surface, keeping the clamp curve", "[geometry]") {
  // The unit sphere at 0.3 with the clamp patch of the 3D presets (p_D = (1, 0, 0), r 0.4),
  // refined to 0.05 at the load point (-1, 0, 0) and at the clamp rim (growth 0.3 per unit).
  const std::array<double, 3> c = {1, 0, 0}, p_n = {-1, 0, 0};
  const double r = 0.4;
  const Boundary in = test::icosphere(5);
  RemeshOptions opt;
  opt.target_edge = 0.3;
  opt.clamp_center = c;
  opt.clamp_radius = r;
  const Boundary coarse = remesh_surface(in, opt);
  opt.size = [&](const std::array<double, 3>& x) {
    return std::min(0.05 + 0.3 * dist(x, p_n), 0.05 + 0.3 * std::abs(dist(x, c) - r));
  };
  opt.min_edge = 0.025;
  const Boundary out = remesh_surface(in, opt);
  const auto check = check_boundary(out);
  INFO(check.reason);
  REQUIRE(check.ok);
  CHECK(out.n_points() > 3 * coarse.n_points());
  // Edges near p_N (within 0.05) and on the rim are near the wanted 0.05: levels 0.15, 0.075,
  // 0.0375 (a level t remeshes where the size wants < 1.5 t), edges up to 4/3 t; far away they
  // stay near 0.3.
  double near_load = 0, far = 0, rim = 0, max_off_sphere = 0;
  for (std::int64_t f = 0; f < out.n_facets(); ++f)
    for (int k = 0; k < 3; ++k) {
      const auto a = out.point(out.facet(f)[k]), b = out.point(out.facet(f)[(k + 1) % 3]);
      const double l = std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
      if (dist(a, p_n) < 0.05) near_load = std::max(near_load, l);
      if (std::abs(dist(a, c) - r) < 1e-12 && std::abs(dist(b, c) - r) < 1e-12) rim = std::max(rim, l);
      if (a[1] > 0.9) far = std::max(far, l);
    }
  for (std::int64_t i = 0; i < out.n_points(); ++i)
    max_off_sphere = std::max(max_off_sphere, std::abs(dist(out.point(i), {0, 0, 0}) - 1));
  CHECK(near_load < 0.1);
  CHECK(rim < 0.1);
  CHECK(far > 0.2);
  // On the input (the level-5 icosphere: edges of 0.03-0.04, off the sphere by up to ~3e-4), not
  // on the coarse level's chords (0.3: sagitta 0.011).
  CHECK(max_off_sphere < 5e-4);
  // The clamp patch is still exactly the facet test, with its area near the cap's, 2 pi 0.08.
  const auto patch = facets_in_ball(out, c, r);
  double area = 0;
  for (int f : patch) area += triangle_area(out, f);
  CHECK(area == Approx(2 * std::numbers::pi * 0.08).epsilon(0.02));
  for (std::int64_t f = 0; f < out.n_facets(); ++f) {
    if (std::binary_search(patch.begin(), patch.end(), int(f))) continue;
    double dmax = 0;
    for (int v : out.facet(f)) dmax = std::max(dmax, dist(out.point(v), c));
    CHECK(dmax > r * (1 + 1e-9));
  }
}

TEST_CASE("remesh_surface rejects bad input", "[geometry]") {
  const Boundary in = test::icosphere(1);
  RemeshOptions opt;
  CHECK_THROWS_AS(remesh_surface(in, opt), std::invalid_argument);  // no target
  opt.target_edge = 0.2;
  opt.clamp_center = std::array<double, 3>{0, 0, 1};
  CHECK_THROWS_AS(remesh_surface(in, opt), std::invalid_argument);  // no radius
  opt.clamp_center.reset();
  Boundary open = in;
  open.facets.resize(open.facets.size() - 3);
  CHECK_THROWS_AS(remesh_surface(open, opt), std::invalid_argument);
  CHECK_THROWS_AS(remesh_surface(polygon_boundary({0, 0, 1, 0, 0, 1}), opt), std::invalid_argument);
}

TEST_CASE("remesh_surface with a clamp sphere that misses the surface", "[geometry]") {
  RemeshOptions opt;
  opt.target_edge = 0.2;
  opt.clamp_center = std::array<double, 3>{0, 0, 3};
  opt.clamp_radius = 0.5;
  const Boundary out = remesh_surface(test::icosphere(2), opt);
  CHECK(check_boundary(out).ok);
  CHECK(facets_in_ball(out, *opt.clamp_center, opt.clamp_radius).empty());
}

TEST_CASE("facets_in_ball", "[geometry]") {
  const Boundary square = polygon_boundary({0, 0, 1, 0, 1, 1, 0, 1});
  CHECK(facets_in_ball(square, {0.5, 0, 0}, 0.5) == std::vector<int>{0});
  CHECK(facets_in_ball(square, {0.5, 0, 0}, std::sqrt(1.25)) == std::vector<int>{0, 1, 2, 3});
  const Boundary box = test::box_surface({0, 0, 0}, {1, 1, 1});
  CHECK(facets_in_ball(box, {0.5, 0.5, 0}, std::sqrt(0.5)) == std::vector<int>{0, 1});
  CHECK(facets_in_ball(box, {0.5, 0.5, 0}, 0.7).empty());
}

TEST_CASE("remesh_surface and check_boundary timings on 50k-100k triangles", "[slow]") {
  using clock = std::chrono::steady_clock;
  auto seconds_since = [](clock::time_point t0) {
    return std::chrono::duration<double>(clock::now() - t0).count();
  };
  const Boundary in = test::bumpy_surface(5);  // 20480 triangles
  RemeshOptions opt;
  opt.target_edge = 0.0145;
  auto t0 = clock::now();
  const Boundary big = remesh_surface(in, opt);
  const double t_big = seconds_since(t0);
  t0 = clock::now();
  const auto check = check_boundary(big);
  const double t_check = seconds_since(t0);
  INFO(check.reason);
  CHECK(check.ok);

  opt.target_edge = 0.02;
  const Boundary mid = remesh_surface(in, opt);
  t0 = clock::now();
  const Boundary plain = remesh_surface(mid, opt);
  const double t_plain = seconds_since(t0);
  opt.clamp_center = std::array<double, 3>{mid.points[0], mid.points[1], mid.points[2]};
  opt.clamp_radius = 0.4;
  t0 = clock::now();
  const Boundary clamped = remesh_surface(mid, opt);
  const double t_clamp = seconds_since(t0);
  CHECK(check_boundary(clamped).ok);
  WARN("remesh " << in.n_facets() << " -> " << big.n_facets() << " triangles: " << t_big
                 << " s; check_boundary on " << big.n_facets() << ": " << t_check << " s; remesh "
                 << mid.n_facets() << " -> " << plain.n_facets() << ": " << t_plain
                 << " s; clamped remesh " << mid.n_facets() << " -> " << clamped.n_facets() << ": "
                 << t_clamp << " s");
}
