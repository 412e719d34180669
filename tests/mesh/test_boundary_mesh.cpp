/// mesh_boundary: the mesh of the inside of a given polygon / closed triangle surface keeps that
/// boundary exactly (same points at the same indices, same segments / triangles), fills the
/// exact area / volume, grades towards small point sizes, passes the quality gate and is
/// deterministic.
#include <algorithm>
#include <array>
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <iostream>
#include <map>
#include <numbers>
#include <set>
#include <stdexcept>

#include "hypershape/mesh/boundary_mesher.hpp"
#include "hypershape/mesh/gmsh_mesher.hpp"
#include "hypershape/mesh/quality.hpp"
#include "support/helpers.hpp"

using namespace hypershape;

namespace {

constexpr double pi = std::numbers::pi;

/// A smooth non-convex star r(t) = r0 + a cos(k t), n points counter-clockwise.
geometry::Boundary star(int n, double r0 = 0.75, double a = 0.2, int k = 5) {
  std::vector<double> xy;
  for (int i = 0; i < n; ++i) {
    const double t = 2 * pi * i / n, r = r0 + a * std::cos(k * t);
    xy.push_back(r * std::cos(t));
    xy.push_back(r * std::sin(t));
  }
  return geometry::polygon_boundary(std::move(xy));
}

double polygon_area(const geometry::Boundary& b) {
  double s = 0;
  for (std::int64_t f = 0; f < b.n_facets(); ++f) {
    const auto p = b.point(b.facet(f)[0]), q = b.point(b.facet(f)[1]);
    s += p[0] * q[1] - p[1] * q[0];
  }
  return s / 2;
}

/// Unit icosphere: an icosahedron with each triangle split in 4 `level` times, projected to the
/// sphere, then every point scaled by radius(unit direction). Outward right-hand normals.
template <class Radius>
geometry::Boundary icosphere(int level, Radius radius) {
  const double t = (1 + std::sqrt(5.0)) / 2;
  std::vector<std::array<double, 3>> p = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                                          {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                                          {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::array<int, 3>> tri = {
      {0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
      {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
      {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  auto unit = [](std::array<double, 3> x) {
    const double r = std::sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
    return std::array<double, 3>{x[0] / r, x[1] / r, x[2] / r};
  };
  for (auto& x : p) x = unit(x);
  for (int l = 0; l < level; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      if (auto it = mid.find(key); it != mid.end()) return it->second;
      p.push_back(
          unit({(p[a][0] + p[b][0]) / 2, (p[a][1] + p[b][1]) / 2, (p[a][2] + p[b][2]) / 2}));
      return mid[key] = int(p.size()) - 1;
    };
    std::vector<std::array<int, 3>> next;
    for (auto [a, b, c] : tri) {
      const int ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
      next.insert(next.end(), {{a, ab, ca}, {b, bc, ab}, {c, ca, bc}, {ab, bc, ca}});
    }
    tri = std::move(next);
  }
  geometry::Boundary b;
  b.dim = 3;
  for (const auto& x : p) {
    const double r = radius(x);
    for (int k = 0; k < 3; ++k) b.points.push_back(r * x[k]);
  }
  for (const auto& f : tri) b.facets.insert(b.facets.end(), f.begin(), f.end());
  return b;
}

geometry::Boundary sphere(int level) {
  return icosphere(level, [](const std::array<double, 3>&) { return 1.0; });
}

/// A sphere with a deep dimple at +z and a bump at +x: not convex.
geometry::Boundary bumped_sphere(int level) {
  return icosphere(level, [](const std::array<double, 3>& u) {
    const double dz = (u[0] * u[0] + u[1] * u[1] + (u[2] - 1) * (u[2] - 1));
    const double dx = ((u[0] - 1) * (u[0] - 1) + u[1] * u[1] + u[2] * u[2]);
    return 1.0 - 0.4 * std::exp(-dz / 0.15) + 0.3 * std::exp(-dx / 0.2);
  });
}

/// The unit icosphere squashed to semi-axes 1.5, 0.8, 0.5: its flat sides have nearly coplanar
/// triangles whose shared edge is the longer diagonal (gmsh leaves slivers there).
geometry::Boundary ellipsoid(int level) {
  auto b = sphere(level);
  for (std::size_t i = 0; i < b.points.size(); i += 3)
    b.points[i] *= 1.5, b.points[i + 1] *= 0.8, b.points[i + 2] *= 0.5;
  return b;
}

/// (1/6) sum x0 . (x1 x x2): the volume enclosed by an outward-oriented closed surface.
double enclosed_volume(const geometry::Boundary& b) {
  double s = 0;
  for (std::int64_t f = 0; f < b.n_facets(); ++f) {
    const auto x = b.point(b.facet(f)[0]), y = b.point(b.facet(f)[1]), z = b.point(b.facet(f)[2]);
    s += x[0] * (y[1] * z[2] - y[2] * z[1]) - x[1] * (y[0] * z[2] - y[2] * z[0]) +
         x[2] * (y[0] * z[1] - y[1] * z[0]);
  }
  return s / 6;
}

/// Total |measure| of the cells.
double mesh_measure(const mesh::MeshData& m) {
  const int nv = m.dim + 1;
  double s = 0;
  for (std::int64_t c = 0; c < m.n_cells(); ++c) {
    const double* x[4];
    for (int a = 0; a < nv; ++a) x[a] = &m.coords[std::size_t(m.cells[c * nv + a]) * m.dim];
    if (m.dim == 2) {
      s += std::abs((x[1][0] - x[0][0]) * (x[2][1] - x[0][1]) -
                    (x[1][1] - x[0][1]) * (x[2][0] - x[0][0])) /
           2;
    } else {
      double e[3][3];
      for (int a = 0; a < 3; ++a)
        for (int k = 0; k < 3; ++k) e[a][k] = x[a + 1][k] - x[0][k];
      s += std::abs(e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) -
                    e[0][1] * (e[1][0] * e[2][2] - e[1][2] * e[2][0]) +
                    e[0][2] * (e[1][0] * e[2][1] - e[1][1] * e[2][0])) /
           6;
    }
  }
  return s;
}

/// Facets (sorted vertex indices) that belong to exactly one cell.
std::set<std::vector<int>> boundary_facets(const mesh::MeshData& m) {
  const int nv = m.dim + 1;
  std::map<std::vector<int>, int> count;
  for (std::int64_t c = 0; c < m.n_cells(); ++c)
    for (int skip = 0; skip < nv; ++skip) {
      std::vector<int> f;
      for (int a = 0; a < nv; ++a)
        if (a != skip) f.push_back(m.cells[c * nv + a]);
      std::sort(f.begin(), f.end());
      ++count[f];
    }
  std::set<std::vector<int>> once;
  for (const auto& [f, k] : count)
    if (k == 1) once.insert(f);
  return once;
}

std::set<std::vector<int>> input_facets(const geometry::Boundary& b) {
  std::set<std::vector<int>> s;
  for (std::int64_t f = 0; f < b.n_facets(); ++f) {
    std::vector<int> v(b.facet(f).begin(), b.facet(f).end());
    std::sort(v.begin(), v.end());
    s.insert(v);
  }
  return s;
}

/// Every cell edge as a sorted pair.
std::set<std::pair<int, int>> cell_edges(const mesh::MeshData& m) {
  const int nv = m.dim + 1;
  std::set<std::pair<int, int>> e;
  for (std::int64_t c = 0; c < m.n_cells(); ++c)
    for (int a = 0; a < nv; ++a)
      for (int b = a + 1; b < nv; ++b)
        e.insert(std::minmax(m.cells[c * nv + a], m.cells[c * nv + b]));
  return e;
}

/// What every mesh of a boundary must satisfy: boundary points first at their exact coordinates,
/// the boundary facets exactly the input's, the exact measure, no orphan or inverted cell, and
/// the default quality gate.
mesh::MeshQuality check_boundary_mesh(const geometry::Boundary& b, const mesh::MeshData& m,
                                      double expected_measure) {
  REQUIRE(m.dim == b.dim);
  REQUIRE(m.n_cells() > 0);
  REQUIRE(m.n_vertices() >= b.n_points());
  for (std::size_t i = 0; i < b.points.size(); ++i) REQUIRE(m.coords[i] == b.points[i]);
  std::vector<char> used(std::size_t(m.n_vertices()), 0);
  for (int v : m.cells) {
    REQUIRE(v >= 0);
    REQUIRE(v < m.n_vertices());
    used[v] = 1;
  }
  CHECK(std::count(used.begin(), used.end(), 0) == 0);
  CHECK(boundary_facets(m) == input_facets(b));
  CHECK(mesh_measure(m) == Approx(expected_measure).epsilon(1e-12));
  const auto q = mesh::mesh_quality(m);
  CHECK(q.n_inverted == 0);
  std::string why;
  const bool good = mesh::passes(q, mesh::QualityGate::defaults(b.dim), &why);
  INFO("min angle " << q.min_angle_deg << ", min shape " << q.min_shape << ": " << why);
  CHECK(good);
  return q;
}

/// Mean length of the edges of the cells whose centroid satisfies `where`.
template <class Where>
double mean_edge(const mesh::MeshData& m, Where where) {
  const int nv = m.dim + 1;
  double sum = 0;
  std::int64_t n = 0;
  for (std::int64_t c = 0; c < m.n_cells(); ++c) {
    double centroid[3] = {0, 0, 0};
    for (int a = 0; a < nv; ++a)
      for (int k = 0; k < m.dim; ++k)
        centroid[k] += m.coords[std::size_t(m.cells[c * nv + a]) * m.dim + k] / nv;
    if (!where(centroid)) continue;
    for (int a = 0; a < nv; ++a)
      for (int b = a + 1; b < nv; ++b) {
        const double* x = &m.coords[std::size_t(m.cells[c * nv + a]) * m.dim];
        const double* y = &m.coords[std::size_t(m.cells[c * nv + b]) * m.dim];
        double d = 0;
        for (int k = 0; k < m.dim; ++k) d += (x[k] - y[k]) * (x[k] - y[k]);
        sum += std::sqrt(d), ++n;
      }
  }
  return n ? sum / double(n) : 0.0;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

TEST_CASE("a star polygon meshes to exactly its boundary", "[mesh][boundary_mesh]") {
  const auto b = star(400);
  mesh::BoundaryMeshOptions opt;
  opt.h = 0.05;
  const auto m = mesh::mesh_boundary(b, opt);
  check_boundary_mesh(b, m, polygon_area(b));
  // Every polygon segment is a mesh edge (and so no vertex was added on the polygon).
  const auto edges = cell_edges(m);
  for (std::int64_t f = 0; f < b.n_facets(); ++f)
    CHECK(edges.contains(std::minmax(b.facet(f)[0], b.facet(f)[1])));
  CHECK(m.n_vertices() > b.n_points());
  CHECK(mesh::mesh_quality(m).max_edge <= 1.5 * opt.h);

  SECTION("deterministic") {
    (void)mesh::mesh_boundary(star(300, 0.8, 0.1, 3), opt);  // something else in between
    (void)mesh::mesh_disk(mesh::MeshOptions{}, std::nullopt);
    CHECK(hstest::same_mesh(m, mesh::mesh_boundary(b, opt)));
  }
}

TEST_CASE("small point sizes refine the polygon's mesh locally", "[mesh][boundary_mesh]") {
  const auto b = star(400);
  mesh::BoundaryMeshOptions opt;
  opt.h = 0.08;
  opt.point_sizes.assign(std::size_t(b.n_points()), opt.h);
  // Small near points 0 and 200 (the tip at angle 0 and the notch at angle pi).
  for (int i : {0, 200})
    for (int d = -6; d <= 6; ++d) opt.point_sizes[std::size_t((i + d + 400) % 400)] = 0.004;
  const auto m = mesh::mesh_boundary(b, opt);
  check_boundary_mesh(b, m, polygon_area(b));
  // The same polygon without point sizes, for comparison.
  mesh::BoundaryMeshOptions plain;
  plain.h = opt.h;
  const auto m_plain = mesh::mesh_boundary(b, plain);
  const auto p0 = b.point(0), p1 = b.point(200);
  auto dist = [&](const double* x) {
    return std::min(std::hypot(x[0] - p0[0], x[1] - p0[1]), std::hypot(x[0] - p1[0], x[1] - p1[1]));
  };
  auto near = [&](const double* x) { return dist(x) < 0.03; };
  auto far = [&](const double* x) { return dist(x) > 0.4; };
  const double near_sized = mean_edge(m, near), near_plain = mean_edge(m_plain, near);
  const double far_sized = mean_edge(m, far), far_plain = mean_edge(m_plain, far);
  INFO("mean edge near the small sizes " << near_sized << " (without them " << near_plain
                                         << "), far " << far_sized << " (" << far_plain << ")");
  CHECK(near_sized > 0);
  CHECK(near_sized < 0.8 * near_plain);
  CHECK(near_sized < 0.01);
  auto n_cells_near = [&](const mesh::MeshData& mesh) {
    std::int64_t n = 0;
    for (std::int64_t c = 0; c < mesh.n_cells(); ++c) {
      double x[2] = {0, 0};
      for (int a = 0; a < 3; ++a)
        for (int k = 0; k < 2; ++k)
          x[k] += mesh.coords[std::size_t(mesh.cells[c * 3 + a]) * 2 + k] / 3;
      n += dist(x) < 0.05;
    }
    return n;
  };
  INFO("cells within 0.05: " << n_cells_near(m) << " (without point sizes " << n_cells_near(m_plain)
                             << ")");
  CHECK(n_cells_near(m) > 2 * n_cells_near(m_plain));
  CHECK(far_sized == Approx(far_plain).epsilon(0.1));  // local: elsewhere unchanged
  CHECK(m_plain.n_cells() < m.n_cells());
}

TEST_CASE("a polygon resolved much finer than h meshes quickly and well", "[mesh][boundary_mesh]") {
  // About 2000 segments of length ~0.003 over a [-1, 1]^2 shape, h = 0.02.
  const auto b = star(2000, 0.8, 0.15, 7);
  mesh::BoundaryMeshOptions opt;
  opt.h = 0.02;
  const auto t0 = std::chrono::steady_clock::now();
  const auto m = mesh::mesh_boundary(b, opt);
  const double t = seconds_since(t0);
  const auto q = check_boundary_mesh(b, m, polygon_area(b));
  INFO("2000 segments, h 0.02: " << m.n_vertices() << " vertices, " << m.n_cells() << " cells in "
                                 << t << " s; min angle " << q.min_angle_deg);
  CHECK(q.max_edge <= 1.5 * opt.h);
  CHECK(t < 10.0);
}

TEST_CASE("a closed surface is filled with tetrahedra without remeshing it",
          "[mesh][boundary_mesh]") {
  // Level-3 icospheres have edges of 0.10-0.13: h = 0.12 matches them.
  const int which = GENERATE(0, 1, 2);
  const auto b = which == 0 ? sphere(3) : which == 1 ? bumped_sphere(3) : ellipsoid(3);
  INFO((which == 0 ? "sphere" : which == 1 ? "bumped sphere" : "ellipsoid"));
  mesh::BoundaryMeshOptions opt;
  opt.h = 0.12;
  const auto m = mesh::mesh_boundary(b, opt);
  check_boundary_mesh(b, m, enclosed_volume(b));
  CHECK(m.n_vertices() > b.n_points());
  // Edges between interior vertices: h is their typical length (gmsh's own 3D sizes give edges
  // 1.36x longer). The ellipsoid's surface is coarser than h in places, and the size grows
  // to match it there.
  if (which < 2) {
    std::vector<double> lengths;
    for (const auto& e : cell_edges(m))
      if (e.first >= b.n_points() && e.second >= b.n_points()) {
        const double* x = &m.coords[std::size_t(e.first) * 3];
        const double* y = &m.coords[std::size_t(e.second) * 3];
        lengths.push_back(std::hypot(x[0] - y[0], x[1] - y[1], x[2] - y[2]) / opt.h);
      }
    std::sort(lengths.begin(), lengths.end());
    double mean = 0;
    for (double l : lengths) mean += l / double(lengths.size());
    const double p99 = lengths[lengths.size() * 99 / 100];
    INFO("interior edges / h: mean " << mean << ", p99 " << p99 << ", max " << lengths.back());
    CHECK(mean > 0.85);
    CHECK(mean < 1.1);
    CHECK(p99 < 1.4);
    CHECK(lengths.back() < 1.75);
  }
  CHECK(hstest::same_mesh(m, mesh::mesh_boundary(b, opt)));
}

TEST_CASE("mesh_boundary rejects malformed input", "[mesh][boundary_mesh]") {
  const auto b = star(50);
  mesh::BoundaryMeshOptions opt;
  opt.h = 0.1;
  opt.point_sizes = {0.1, 0.1};
  CHECK_THROWS_AS(mesh::mesh_boundary(b, opt), std::invalid_argument);
  opt.point_sizes.clear();
  opt.h = 0;
  CHECK_THROWS_AS(mesh::mesh_boundary(b, opt), std::invalid_argument);
  opt.h = 0.1;
  auto open = b;
  open.facets.resize(open.facets.size() - 2);
  CHECK_THROWS_AS(mesh::mesh_boundary(open, opt), std::invalid_argument);
  auto holed = sphere(1);
  holed.facets.resize(holed.facets.size() - 3);
  CHECK_THROWS_AS(mesh::mesh_boundary(holed, opt), std::invalid_argument);
  // A self-intersecting polygon (a bow tie) cannot be meshed: an error, not a bad mesh.
  const auto bow = geometry::polygon_boundary({0, 0, 1, 1, 1, 0, 0, 1});
  CHECK_THROWS_AS(mesh::mesh_boundary(bow, opt), std::runtime_error);
  // gmsh still works afterwards.
  CHECK(mesh::mesh_boundary(b, opt).n_cells() > 0);
}

TEST_CASE("boundary mesh figures", "[.][slow][bench][boundary_mesh]") {
  // Prints size, time and quality for the shapes of the report (not a check).
  auto row = [](const char* name, const geometry::Boundary& b, double h) {
    mesh::BoundaryMeshOptions opt;
    opt.h = h;
    const auto t0 = std::chrono::steady_clock::now();
    const auto m = mesh::mesh_boundary(b, opt);
    const double t = seconds_since(t0);
    const auto q = mesh::mesh_quality(m);
    std::cout << name << " h " << h << ": " << b.n_facets() << " facets, " << m.n_vertices()
              << " vertices, " << m.n_cells() << " cells, " << t << " s, min angle "
              << q.min_angle_deg << ", min shape " << q.min_shape << ", max edge / h "
              << q.max_edge / h << "\n";
  };
  for (double h : {0.02, 0.05, 0.1}) {
    row("star 400", star(400), h);
    row("star 2000", star(2000, 0.8, 0.15, 7), h);
    row("sharp star 300", star(300, 0.6, 0.4, 9), h);
    row("circle 64", star(64, 1.0, 0.0, 1), h);
  }
  for (double h : {0.06, 0.12, 0.25}) {
    row("icosphere 3", sphere(3), h);
    row("bumped icosphere 3", bumped_sphere(3), h);
    row("bumped icosphere 4", bumped_sphere(4), h);
    row("ellipsoid 3", ellipsoid(3), h);
  }
}
