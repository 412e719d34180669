// MeshSampler: P1 / P2 interpolation inside the mesh (exact for linear / quadratic fields), the
// closest-point extension outside (against brute force over every boundary facet), the inside
// flag against the exact signed distance, points exactly on vertices, edges and faces, no NaN,
// and bad input. P2 meshes are built here from P1 meshes (edge midpoints), independently of the
// library.
#include <algorithm>
#include <array>
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <ctime>
#include <functional>
#include <iostream>
#include <map>
#include <optional>
#include <random>
#include <span>
#include <stdexcept>
#include <tuple>
#include <utility>
#include <vector>

#include "geometry/shapes.hpp"
#include "hypershape/geometry/distance.hpp"
#include "hypershape/mesh/boundary_mesher.hpp"
#include "hypershape/mesh/gmsh_mesher.hpp"
#include "hypershape/sampling/grid.hpp"
#include "hypershape/sampling/mesh_sampler.hpp"

using namespace hypershape;
namespace hg = hypershape::geometry;
namespace hs = hypershape::sampling;
using V3 = std::array<double, 3>;

namespace {

// ---- meshes ------------------------------------------------------------------------------------

/// An FE mesh as MeshSampler takes it.
struct FeMesh {
  int dim = 0, degree = 1;
  std::vector<double> nodes;
  std::vector<std::int64_t> cells;
  hg::Boundary boundary;
  std::int64_t n_nodes() const { return std::int64_t(nodes.size()) / dim; }
};

FeMesh p1_mesh(const mesh::MeshData& m, hg::Boundary b) {
  FeMesh f;
  f.dim = m.dim;
  f.nodes = m.coords;
  f.cells.assign(m.cells.begin(), m.cells.end());
  f.boundary = std::move(b);
  return f;
}

/// The P2 mesh of a P1 mesh: vertices first, then one midpoint per edge; cells in VTK order
/// (triangle v0 v1 v2 m01 m12 m20, tetrahedron v0 v1 v2 v3 m01 m12 m20 m03 m13 m23).
FeMesh p2_mesh(const FeMesh& p1) {
  const int d = p1.dim, nv = d + 1;
  static const int tri[3][2] = {{0, 1}, {1, 2}, {2, 0}};
  static const int tet[6][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};
  FeMesh p2 = p1;
  p2.degree = 2;
  p2.cells.clear();
  std::map<std::pair<std::int64_t, std::int64_t>, std::int64_t> mid;
  for (std::size_t c = 0; c < p1.cells.size() / std::size_t(nv); ++c) {
    const std::int64_t* v = &p1.cells[c * std::size_t(nv)];
    p2.cells.insert(p2.cells.end(), v, v + nv);
    for (int e = 0; e < (d == 2 ? 3 : 6); ++e) {
      const int* ab = d == 2 ? tri[e] : tet[e];
      const auto key = std::minmax(v[ab[0]], v[ab[1]]);
      auto it = mid.find(key);
      if (it == mid.end()) {
        const std::int64_t id = p2.n_nodes();
        for (int k = 0; k < d; ++k)
          p2.nodes.push_back(0.5 * (p2.nodes[std::size_t(key.first * d + k)] +
                                    p2.nodes[std::size_t(key.second * d + k)]));
        it = mid.emplace(key, id).first;
      }
      p2.cells.push_back(it->second);
    }
  }
  return p2;
}

/// The boundary of a mesh as a Boundary whose points are all the mesh vertices (the faces that
/// belong to one cell, oriented outward).
hg::Boundary extract_boundary(const mesh::MeshData& m) {
  const int d = m.dim, nv = d + 1;
  std::map<std::array<int, 3>, std::pair<int, std::array<int, 4>>> faces;  // sorted -> count, cell
  for (std::int64_t c = 0; c < m.n_cells(); ++c) {
    std::array<int, 4> v{};
    for (int i = 0; i < nv; ++i) v[std::size_t(i)] = m.cells[std::size_t(c * nv + i)];
    for (int o = 0; o < nv; ++o) {
      std::array<int, 3> k{-1, -1, -1};
      for (int i = 0, j = 0; i < nv; ++i)
        if (i != o) k[std::size_t(j++)] = v[std::size_t(i)];
      if (d == 3)
        std::sort(k.begin(), k.end());
      else if (k[1] < k[0])
        std::swap(k[0], k[1]);
      auto& e = faces[k];
      ++e.first;
      std::array<int, 4> face_and_opposite{k[0], k[1], k[2], v[std::size_t(o)]};
      e.second = face_and_opposite;
    }
  }
  hg::Boundary b;
  b.dim = d;
  b.points = m.coords;
  const auto x = [&](int i) {
    return V3{m.coords[std::size_t(i * d)], m.coords[std::size_t(i * d + 1)],
              d == 3 ? m.coords[std::size_t(i * d + 2)] : 0.0};
  };
  for (const auto& [key, e] : faces) {
    if (e.first != 1) continue;
    auto f = e.second;
    const V3 a = x(f[0]), bb = x(f[1]), o = x(f[3]);
    V3 n;
    if (d == 2) {
      n = {bb[1] - a[1], a[0] - bb[0], 0};
    } else {
      const V3 c = x(f[2]);
      const V3 u{bb[0] - a[0], bb[1] - a[1], bb[2] - a[2]},
          w{c[0] - a[0], c[1] - a[1], c[2] - a[2]};
      n = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
    }
    if (n[0] * (a[0] - o[0]) + n[1] * (a[1] - o[1]) + n[2] * (a[2] - o[2]) < 0)
      std::swap(f[0], f[1]);
    b.facets.insert(b.facets.end(), f.begin(), f.begin() + d);
  }
  return b;
}

FeMesh star_mesh(double h) {
  const hg::Boundary b = hg::test::star_polygon(5, 120);
  mesh::BoundaryMeshOptions opt;
  opt.h = h;
  return p1_mesh(mesh::mesh_boundary(b, opt), b);
}

FeMesh bumpy_mesh(int subdivisions, double h) {
  const hg::Boundary b = hg::test::bumpy_surface(subdivisions);
  mesh::BoundaryMeshOptions opt;
  opt.h = h;
  return p1_mesh(mesh::mesh_boundary(b, opt), b);
}

// ---- fields ------------------------------------------------------------------------------------

using Field = std::function<std::array<double, 2>(const double*)>;

std::array<double, 2> linear(const double* x, int dim) {
  const double z = dim == 3 ? x[2] : 0.0;
  return {1 + 2 * x[0] - 3 * x[1] + 0.5 * z, -0.5 + 0.25 * x[0] + x[1] - z};
}
std::array<double, 2> quadratic(const double* x, int dim) {
  const double z = dim == 3 ? x[2] : 0.0;
  return {x[0] * x[0] - x[0] * x[1] + 2 * x[1] * x[1] + x[0] - 1 + z * z - 0.3 * x[1] * z,
          3 * x[0] * x[1] - x[1] * x[1] + 0.2 + x[0] * z - 2 * z};
}

std::vector<double> nodal(const FeMesh& m, const Field& f) {
  std::vector<double> v;
  for (std::int64_t i = 0; i < m.n_nodes(); ++i) {
    const auto y = f(&m.nodes[std::size_t(i * m.dim)]);
    v.insert(v.end(), y.begin(), y.end());
  }
  return v;
}

// ---- brute-force closest point -----------------------------------------------------------------

V3 sub(const V3& a, const V3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
V3 add_scaled(const V3& a, const V3& b, double s) {
  return {a[0] + s * b[0], a[1] + s * b[1], a[2] + s * b[2]};
}
double dot(const V3& a, const V3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
double norm(const V3& a) { return std::sqrt(dot(a, a)); }

V3 closest_on_segment(const V3& p, const V3& a, const V3& b) {
  const V3 ab = sub(b, a);
  return add_scaled(a, ab, std::clamp(dot(sub(p, a), ab) / dot(ab, ab), 0.0, 1.0));
}

// Ericson, Real-Time Collision Detection, 5.1.5.
V3 closest_on_triangle(const V3& p, const V3& a, const V3& b, const V3& c) {
  const V3 ab = sub(b, a), ac = sub(c, a), ap = sub(p, a);
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const V3 bp = sub(p, b);
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return add_scaled(a, ab, d1 / (d1 - d3));
  const V3 cp = sub(p, c);
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return add_scaled(a, ac, d2 / (d2 - d6));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0)
    return add_scaled(b, sub(c, b), (d4 - d3) / ((d4 - d3) + (d5 - d6)));
  const double denom = 1 / (va + vb + vc);
  return add_scaled(add_scaled(a, ab, vb * denom), ac, vc * denom);
}

V3 bpoint(const hg::Boundary& b, std::int64_t i) {
  const auto p = b.point(i);
  return {p[0], p[1], b.dim == 3 ? p[2] : 0.0};
}

/// The closest boundary point to p by brute force; nullopt when another facet holds a different
/// point at (nearly) the same distance (p on the medial axis: the extension may take either).
std::optional<V3> brute_closest(const hg::Boundary& b, const V3& p) {
  std::vector<std::pair<double, V3>> c;
  for (std::int64_t f = 0; f < b.n_facets(); ++f) {
    const auto v = b.facet(f);
    const V3 q = b.dim == 2
                     ? closest_on_segment(p, bpoint(b, v[0]), bpoint(b, v[1]))
                     : closest_on_triangle(p, bpoint(b, v[0]), bpoint(b, v[1]), bpoint(b, v[2]));
    c.push_back({norm(sub(p, q)), q});
  }
  const auto best = *std::min_element(
      c.begin(), c.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
  for (const auto& [d, q] : c)
    if (d < best.first + 1e-9 && norm(sub(q, best.second)) > 1e-7) return std::nullopt;
  return best.second;
}

// ---- the check ---------------------------------------------------------------------------------

std::vector<double> random_points(int dim, int n, double half, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-half, half);
  std::vector<double> x(std::size_t(dim * n));
  for (double& c : x) c = u(rng);
  return x;
}

struct Counts {
  int inside = 0, outside = 0, ambiguous = 0;
};

/// Samples `f` (interpolated at the nodes of `m`) at `points` and checks every value: f(x)
/// inside (exact for fields in the FE space), f(closest boundary point) outside; and the inside
/// flags against the exact signed distance.
Counts check_sampler(const FeMesh& m, const std::vector<double>& points, const Field& f) {
  const hs::MeshSampler sampler(m.dim, m.degree, m.nodes, m.cells, m.boundary, points);
  const hg::SignedDistance sd(m.boundary);
  const std::size_t d = std::size_t(m.dim), n = points.size() / d;
  REQUIRE(sampler.n_points() == n);
  REQUIRE(sampler.n_nodes() == std::size_t(m.n_nodes()));
  const std::vector<double> values = sampler.interpolate(nodal(m, f), 2);
  REQUIRE(values.size() == 2 * n);
  CHECK(sampler.n_snapped() == 0);
  Counts counts;
  for (std::size_t p = 0; p < n; ++p) {
    const double* x = &points[p * d];
    const std::span<const double> xs(x, d);
    INFO("point " << p << " (" << x[0] << ", " << x[1] << ", " << (d == 3 ? x[2] : 0.0) << ")");
    REQUIRE(std::isfinite(values[2 * p]));
    REQUIRE(std::isfinite(values[2 * p + 1]));
    const bool inside = sampler.inside()[p] != 0;
    CHECK(inside == (sd.side(xs) <= 0));
    CHECK(inside == (sd(xs) <= 0));
    std::array<double, 2> expected;
    if (inside) {
      ++counts.inside;
      expected = f(x);
    } else {
      ++counts.outside;
      const auto q = brute_closest(m.boundary, {x[0], x[1], d == 3 ? x[2] : 0.0});
      if (!q) {
        ++counts.ambiguous;
        continue;
      }
      expected = f(q->data());
    }
    // Inside: the interpolant of a field in the FE space is the field, to round-off. Outside:
    // the same at a closest point computed two ways (tree and brute force), so a little looser.
    const double tol = inside ? 1e-12 : 1e-11;
    CHECK(values[2 * p] == Approx(expected[0]).margin(tol).epsilon(0));
    CHECK(values[2 * p + 1] == Approx(expected[1]).margin(tol).epsilon(0));
  }
  return counts;
}

}  // namespace

TEST_CASE("MeshSampler: exact inside, closest-point extension outside, 2D",
          "[sampling][mesh_sampler]") {
  const FeMesh p1 = star_mesh(0.1);
  const FeMesh p2 = p2_mesh(p1);
  const auto lin = [](const double* x) { return linear(x, 2); };
  const auto quad = [](const double* x) { return quadratic(x, 2); };
  std::vector<double> points = random_points(2, 3000, 1.4, 11);
  const std::vector<double> grid = hs::grid_points(2, 41);
  points.insert(points.end(), grid.begin(), grid.end());
  for (const auto& [m, f, what] :
       {std::tuple{&p1, Field(lin), "P1, linear"}, std::tuple{&p2, Field(lin), "P2, linear"},
        std::tuple{&p2, Field(quad), "P2, quadratic"}}) {
    INFO(what);
    const Counts c = check_sampler(*m, points, f);
    CHECK(c.inside > 1000);
    CHECK(c.outside > 1000);
    CHECK(c.ambiguous < 20);
  }
}

TEST_CASE("MeshSampler: exact inside, closest-point extension outside, 3D",
          "[sampling][mesh_sampler]") {
  const FeMesh p1 = bumpy_mesh(2, 0.25);
  const FeMesh p2 = p2_mesh(p1);
  const auto lin = [](const double* x) { return linear(x, 3); };
  const auto quad = [](const double* x) { return quadratic(x, 3); };
  std::vector<double> points = random_points(3, 1500, 1.3, 12);
  const std::vector<double> grid = hs::grid_points(3, 11);
  points.insert(points.end(), grid.begin(), grid.end());
  for (const auto& [m, f, what] :
       {std::tuple{&p1, Field(lin), "P1, linear"}, std::tuple{&p2, Field(lin), "P2, linear"},
        std::tuple{&p2, Field(quad), "P2, quadratic"}}) {
    INFO(what);
    const Counts c = check_sampler(*m, points, f);
    CHECK(c.inside > 300);
    CHECK(c.outside > 300);
    CHECK(c.ambiguous < 20);
  }
}

TEST_CASE("MeshSampler: boundaries whose points are all the mesh vertices",
          "[sampling][mesh_sampler]") {
  mesh::MeshOptions opt;
  opt.h = 0.15;
  for (const int dim : {2, 3}) {
    INFO(dim << "D");
    opt.h = dim == 2 ? 0.1 : 0.3;
    const mesh::MeshData m =
        dim == 2 ? mesh::mesh_disk(opt, std::nullopt) : mesh::mesh_ball(opt, std::nullopt);
    const FeMesh p2 = p2_mesh(p1_mesh(m, extract_boundary(m)));
    const auto quad = [dim](const double* x) { return quadratic(x, dim); };
    std::vector<double> points = random_points(dim, 1000, 1.2, 13);
    const Counts c = check_sampler(p2, points, quad);
    CHECK(c.inside > 100);
    CHECK(c.outside > 100);
  }
}

TEST_CASE("MeshSampler: points exactly on vertices, edges, faces and the boundary",
          "[sampling][mesh_sampler]") {
  SECTION("2D rectangle on grid lines, and every node of a P2 mesh") {
    // Sides on the grid lines of a 17-point grid (spacing 1/8): many points on the boundary,
    // at its corners and (interior vertices of a structured-looking mesh) on mesh vertices.
    const hg::Boundary b = hg::test::rectangle(-0.5, -0.25, 0.5, 0.75, 0.125);
    mesh::BoundaryMeshOptions opt;
    opt.h = 0.125;
    const mesh::MeshData m = mesh::mesh_boundary(b, opt);
    const FeMesh p2 = p2_mesh(p1_mesh(m, b));
    const auto quad = [](const double* x) { return quadratic(x, 2); };
    const std::vector<double> grid = hs::grid_points(2, 17);
    check_sampler(p2, grid, quad);
    const hs::MeshSampler s(2, 2, p2.nodes, p2.cells, p2.boundary, grid);
    int on_boundary = 0;
    for (std::size_t p = 0; p < s.n_points(); ++p) {
      const double x = grid[2 * p], y = grid[2 * p + 1];
      const bool on = ((x == -0.5 || x == 0.5) && y >= -0.25 && y <= 0.75) ||
                      ((y == -0.25 || y == 0.75) && x >= -0.5 && x <= 0.5);
      if (!on) continue;
      ++on_boundary;
      CHECK(s.inside()[p] == 1);
    }
    CHECK(on_boundary == 4 * 8);
    // Every node (vertices and midpoints) as a query point gets its own value back.
    const Counts c = check_sampler(p2, p2.nodes, quad);
    CHECK(c.inside + c.outside == p2.n_nodes());
    const hs::MeshSampler at_nodes(2, 2, p2.nodes, p2.cells, p2.boundary, p2.nodes);
    const std::vector<double> f = nodal(p2, quad);
    const std::vector<double> v = at_nodes.interpolate(f, 2);
    for (std::size_t i = 0; i < f.size(); ++i) CHECK(v[i] == Approx(f[i]).margin(1e-13));
    for (std::int64_t i = 0; i < m.n_vertices(); ++i)
      CHECK(at_nodes.inside()[std::size_t(i)] == 1);  // every vertex is in (or on) the mesh
  }
  SECTION("3D box on grid planes: faces, edges, corners, and every node of a P2 mesh") {
    const hg::Boundary b = hg::test::box_surface({-0.5, -0.5, -0.5}, {0.5, 0.5, 0.5});
    mesh::BoundaryMeshOptions opt;
    opt.h = 0.5;
    const mesh::MeshData m = mesh::mesh_boundary(b, opt);
    const FeMesh p2 = p2_mesh(p1_mesh(m, b));
    const auto quad = [](const double* x) { return quadratic(x, 3); };
    const std::vector<double> grid = hs::grid_points(3, 9);  // spacing 1/4
    check_sampler(p2, grid, quad);
    const hs::MeshSampler s(3, 2, p2.nodes, p2.cells, p2.boundary, grid);
    int on_boundary = 0;
    for (std::size_t p = 0; p < s.n_points(); ++p) {
      const double* x = &grid[3 * p];
      bool in_box = true, on_face = false;
      for (int k = 0; k < 3; ++k) {
        in_box = in_box && std::abs(x[k]) <= 0.5;
        on_face = on_face || std::abs(x[k]) == 0.5;
      }
      CHECK(s.inside()[p] == (in_box ? 1 : 0));
      on_boundary += in_box && on_face;
    }
    CHECK(on_boundary == 5 * 5 * 5 - 3 * 3 * 3);
    const hs::MeshSampler at_nodes(3, 2, p2.nodes, p2.cells, p2.boundary, p2.nodes);
    const std::vector<double> f = nodal(p2, quad);
    const std::vector<double> v = at_nodes.interpolate(f, 2);
    for (std::size_t i = 0; i < f.size(); ++i) CHECK(v[i] == Approx(f[i]).margin(1e-13));
    for (std::int64_t i = 0; i < m.n_vertices(); ++i) CHECK(at_nodes.inside()[std::size_t(i)] == 1);
  }
}

TEST_CASE("MeshSampler: no NaN anywhere, any number of components, shared SignedDistance",
          "[sampling][mesh_sampler]") {
  const FeMesh p2 = p2_mesh(star_mesh(0.15));
  // Far points, the grid, points on the boundary polygon's vertices and edge midpoints.
  std::vector<double> points = {1e3, -1e3, -50, 0, 0, 0, 1e-300, -1e-300};
  const std::vector<double> grid = hs::grid_points(2, 64);
  points.insert(points.end(), grid.begin(), grid.end());
  for (std::int64_t f = 0; f < p2.boundary.n_facets(); ++f) {
    const auto a = p2.boundary.point(p2.boundary.facet(f)[0]);
    const auto b = p2.boundary.point(p2.boundary.facet(f)[1]);
    points.insert(points.end(), {a[0], a[1], 0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])});
  }
  const hs::MeshSampler s(2, 2, p2.nodes, p2.cells, p2.boundary, points);
  const hg::SignedDistance sd(p2.boundary);
  const hs::MeshSampler shared(2, 2, p2.nodes, p2.cells, p2.boundary, sd, points);
  CHECK(std::equal(s.inside().begin(), s.inside().end(), shared.inside().begin()));

  // A smooth non-polynomial field with 1, 2, 4 and 5 components: the general and the
  // specialised gathers agree, and nothing is NaN.
  for (const int n_comp : {1, 2, 3, 4, 5}) {
    std::vector<double> field;
    for (std::int64_t i = 0; i < p2.n_nodes(); ++i)
      for (int c = 0; c < n_comp; ++c)
        field.push_back(std::sin(3 * p2.nodes[std::size_t(2 * i)] + c) *
                        std::exp(p2.nodes[std::size_t(2 * i + 1)]));
    const std::vector<double> v = s.interpolate(field, n_comp);
    const std::vector<double> w = shared.interpolate(field, n_comp);
    CHECK(v == w);
    CHECK(std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); }));
    if (n_comp >= 2) {
      // Component 0 does not depend on how many components there are.
      std::vector<double> first;
      for (std::int64_t i = 0; i < p2.n_nodes(); ++i)
        first.push_back(field[std::size_t(i * n_comp)]);
      const std::vector<double> u = s.interpolate(first, 1);
      for (std::size_t p = 0; p < s.n_points(); ++p)
        CHECK(v[p * std::size_t(n_comp)] == Approx(u[p]).margin(1e-14));
    }
  }
  // Boundary vertices are on the boundary, so inside.
  const std::size_t first_vertex = 4 + grid.size() / 2;
  for (std::int64_t f = 0; f < p2.boundary.n_facets(); ++f)
    CHECK(s.inside()[first_vertex + std::size_t(2 * f)] == 1);
  CHECK(s.inside()[0] == 0);
  CHECK(s.inside()[1] == 0);
  CHECK(s.inside()[2] == 1);
  CHECK(s.inside()[3] == 1);

  SECTION("a mesh with a hole (a missing interior cell) still gives finite values") {
    FeMesh holed = p2;
    for (std::size_t c = 0; c < holed.cells.size() / 6; ++c) {
      bool interior = true;
      for (int k = 0; k < 3; ++k)
        interior = interior && holed.cells[6 * c + std::size_t(k)] >= holed.boundary.n_points();
      if (!interior) continue;
      holed.cells.erase(holed.cells.begin() + std::ptrdiff_t(6 * c),
                        holed.cells.begin() + std::ptrdiff_t(6 * c + 6));
      break;
    }
    REQUIRE(holed.cells.size() == p2.cells.size() - 6);
    const hs::MeshSampler h(2, 2, holed.nodes, holed.cells, holed.boundary, points);
    const std::vector<double> v =
        h.interpolate(nodal(holed, [](const double* x) { return quadratic(x, 2); }), 2);
    CHECK(std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); }));
  }
}

TEST_CASE("MeshSampler rejects bad input", "[sampling][mesh_sampler]") {
  const FeMesh p1 = star_mesh(0.2);
  const FeMesh p2 = p2_mesh(p1);
  const std::vector<double> pts = {0, 0, 0.5, 0.5};
  using E = std::invalid_argument;
  CHECK_THROWS_AS(hs::MeshSampler(3, 1, p1.nodes, p1.cells, p1.boundary, pts), E);
  CHECK_THROWS_AS(hs::MeshSampler(2, 3, p1.nodes, p1.cells, p1.boundary, pts), E);
  const std::vector<std::int64_t> three_cells(p1.cells.begin(), p1.cells.begin() + 9);
  CHECK_THROWS_AS(hs::MeshSampler(2, 2, p1.nodes, three_cells, p1.boundary, pts), E);  // 9 % 6
  CHECK_THROWS_AS(hs::MeshSampler(2, 1, p1.nodes, std::vector<std::int64_t>{}, p1.boundary, pts),
                  E);
  CHECK_THROWS_AS(
      hs::MeshSampler(2, 1, p1.nodes, p1.cells, p1.boundary, std::vector<double>{0, 0, 1}), E);
  CHECK_THROWS_AS(
      hs::MeshSampler(2, 1, p1.nodes, p1.cells, p1.boundary, std::vector<double>{0, std::nan("")}),
      E);
  auto bad_cells = p1.cells;
  bad_cells[4] = p1.n_nodes();
  CHECK_THROWS_AS(hs::MeshSampler(2, 1, p1.nodes, bad_cells, p1.boundary, pts), E);
  // A boundary that is not this mesh's: moved points, or facets that are no cell faces.
  hg::Boundary moved = p1.boundary;
  moved.points[0] += 1e-6;
  CHECK_THROWS_AS(hs::MeshSampler(2, 1, p1.nodes, p1.cells, moved, pts), E);
  hg::Boundary rewired = p1.boundary;
  rewired.facets[1] = 5;  // segment (0, 5): not a mesh edge
  CHECK_THROWS_AS(hs::MeshSampler(2, 1, p1.nodes, p1.cells, rewired, pts), E);
  const hg::Boundary square = hg::test::rectangle(0, 0, 1, 1, 0.5);
  CHECK_THROWS_AS(hs::MeshSampler(2, 1, p1.nodes, p1.cells, square, pts), E);

  const hs::MeshSampler none(2, 2, p2.nodes, p2.cells, p2.boundary, std::vector<double>{});
  CHECK(none.n_points() == 0);
  CHECK(none.interpolate(std::vector<double>(std::size_t(p2.n_nodes()), 1.0), 1).empty());
  const hs::MeshSampler s(2, 2, p2.nodes, p2.cells, p2.boundary, pts);
  std::vector<double> field(std::size_t(p2.n_nodes()) * 3, 1.0), out(6);
  CHECK_NOTHROW(s.interpolate(field, 3, out));
  for (const double v : out) CHECK(v == Approx(1.0).margin(1e-14));  // partition of unity
  CHECK_THROWS_AS(s.interpolate(field, 2, out), E);
  CHECK_THROWS_AS(s.interpolate(field, 0, out), E);
  std::vector<double> short_out(5);
  CHECK_THROWS_AS(s.interpolate(field, 3, short_out), E);
}

// Not run by default: `unit_tests "[timing]"` prints set-up and interpolation times (wall clock
// and CPU time of this process) for the grid sizes of the datasets; nothing is asserted.
TEST_CASE("MeshSampler timings", "[.][slow][timing]") {
  struct Timer {
    std::chrono::steady_clock::time_point wall = std::chrono::steady_clock::now();
    std::clock_t cpu = std::clock();
    double wall_s() const {
      return std::chrono::duration<double>(std::chrono::steady_clock::now() - wall).count();
    }
    double cpu_s() const { return double(std::clock() - cpu) / CLOCKS_PER_SEC; }
  };
  const auto run = [](const FeMesh& m, int n, int repeat) {
    const std::vector<double> grid = hs::grid_points(m.dim, n);
    double build_wall = 1e300, build_cpu = 1e300;
    std::optional<hs::MeshSampler> s;
    for (int r = 0; r < repeat; ++r) {
      s.reset();
      const Timer t;
      s.emplace(m.dim, m.degree, m.nodes, m.cells, m.boundary, grid);
      build_wall = std::min(build_wall, t.wall_s());
      build_cpu = std::min(build_cpu, t.cpu_s());
    }
    std::vector<double> field(std::size_t(m.n_nodes() * m.dim), 0.5);
    std::vector<double> out(s->n_points() * std::size_t(m.dim));
    double interp = 1e300;
    for (int r = 0; r < 5; ++r) {
      const Timer t;
      s->interpolate(field, m.dim, out);
      interp = std::min(interp, t.wall_s());
    }
    // For comparison: the SDF on the same grid (what the grid representation stores beside).
    const Timer t_sdf;
    const hg::SignedDistance sd(m.boundary);
    std::vector<double> sdf(s->n_points());
    sd.evaluate(grid, sdf);
    const double sdf_s = t_sdf.cpu_s();
    // The part of the set-up that is the closest-point queries of the outside points.
    std::vector<double> outside;
    for (std::size_t p = 0; p < s->n_points(); ++p)
      if (!s->inside()[p])
        outside.insert(outside.end(), grid.begin() + std::ptrdiff_t(p * std::size_t(m.dim)),
                       grid.begin() + std::ptrdiff_t((p + 1) * std::size_t(m.dim)));
    std::vector<hg::ClosestPoint> hits(outside.size() / std::size_t(m.dim));
    const Timer t_closest;
    sd.closest(outside, hits);
    const double closest_s = t_closest.cpu_s();
    std::size_t n_in = 0;
    for (const auto f : s->inside()) n_in += f;
    std::cout << m.dim << "D P" << m.degree << ": "
              << m.cells.size() / std::size_t(m.degree == 1 ? m.dim + 1 : (m.dim == 2 ? 6 : 10))
              << " cells, " << m.n_nodes() << " nodes, " << m.boundary.n_facets()
              << " boundary facets; " << n << "^" << m.dim << " grid (" << n_in
              << " inside): set-up " << build_wall * 1e3 << " ms (cpu " << build_cpu * 1e3
              << " ms), interpolate " << m.dim << " components " << interp * 1e3
              << " ms; cpu: closest points of the outside points alone " << closest_s * 1e3
              << " ms, SignedDistance on the grid " << sdf_s * 1e3 << " ms\n";
  };
  {
    const hg::Boundary b = hg::test::star_polygon(7, 600);
    mesh::BoundaryMeshOptions opt;
    opt.h = 0.04;
    const FeMesh p1 = p1_mesh(mesh::mesh_boundary(b, opt), b);
    run(p1, 128, 5);
    run(p2_mesh(p1), 128, 5);
  }
  {
    const FeMesh p1 = bumpy_mesh(4, 0.07);
    run(p1, 64, 2);
    run(p2_mesh(p1), 64, 2);
  }
}
