/// Meshes: every generated or imported cell is positively oriented in PETSc's convention, bad
/// cells are rejected, the disk's clamp ends are mesh vertices, the Dirichlet patch marks
/// exactly the facets between them, and bad mesh files are input errors naming the file.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <set>

#include "hypershape/core/error.hpp"
#include "hypershape/mesh/plex.hpp"
#include "support/helpers.hpp"

using namespace hypershape;

namespace {

/// Signed measure in PETSc's convention (> 0: positively oriented).
double petsc_signed_measure(const mesh::MeshData& m, std::int64_t c) {
  const int nv = m.dim + 1;
  const double* x[4];
  for (int a = 0; a < nv; ++a) x[a] = &m.coords[std::size_t(m.cells[c * nv + a]) * m.dim];
  if (m.dim == 2)
    return (x[1][0] - x[0][0]) * (x[2][1] - x[0][1]) - (x[1][1] - x[0][1]) * (x[2][0] - x[0][0]);
  double e[3][3];
  for (int a = 0; a < 3; ++a)
    for (int k = 0; k < 3; ++k) e[a][k] = x[a + 1][k] - x[0][k];
  const double triple = e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) -
                        e[0][1] * (e[1][0] * e[2][2] - e[1][2] * e[2][0]) +
                        e[0][2] * (e[1][0] * e[2][1] - e[1][1] * e[2][0]);
  return -triple;  // PETSc's reference tetrahedron is left-handed
}

/// Checks the MeshData invariants and the plex built from it (det J > 0 everywhere, the total
/// measure) and returns the plex's minimum det J.
double check_mesh(const mesh::MeshData& m, int dim, double expected_measure, double tol) {
  REQUIRE(m.dim == dim);
  REQUIRE(m.n_cells() > 0);
  REQUIRE(m.cells.size() == std::size_t(m.n_cells()) * (dim + 1));
  std::vector<char> used(m.n_vertices(), 0);
  for (int v : m.cells) {
    REQUIRE(v >= 0);
    REQUIRE(v < m.n_vertices());
    used[v] = 1;
  }
  // No orphan vertices (they would carry free, unconstrained DoFs).
  CHECK(std::count(used.begin(), used.end(), 0) == 0);
  double measure = 0;
  std::int64_t n_bad = 0;
  for (std::int64_t c = 0; c < m.n_cells(); ++c) {
    const double s = petsc_signed_measure(m, c);
    n_bad += s <= 0;
    measure += std::abs(s) / (dim == 2 ? 2.0 : 6.0);
  }
  CHECK(n_bad == 0);
  if (expected_measure > 0) CHECK(measure == Approx(expected_measure).epsilon(tol));

  // Through PETSc, with its own geometry routine, cell by cell.
  core::DMH dm = mesh::create_plex(PETSC_COMM_WORLD, m);
  PetscInt c0, c1;
  HS_PETSC(DMPlexGetHeightStratum(dm, 0, &c0, &c1));
  CHECK(c1 - c0 == m.n_cells());
  double min_det = 1e300;
  for (PetscInt c = c0; c < c1; ++c) {
    double v0[3], J[9], iJ[9], detJ;
    HS_PETSC(DMPlexComputeCellGeometryAffineFEM(dm, c, v0, J, iJ, &detJ));
    min_det = std::min(min_det, detJ);
  }
  CHECK(min_det > 0);
  // And through the space, as the solver sees it.
  std::vector<physics::EffectPtr> none;
  none.push_back(physics::make_neo_hookean(1.0, 0.3));
  physics::Problem p(PETSC_COMM_WORLD, m, std::move(none), hstest::degree(1));
  CHECK(p.space().min_det_jacobian() > 0);
  CHECK(p.space().min_det_jacobian() == Approx(min_det).epsilon(1e-12));
  CHECK(hstest::domain_measure(p) == Approx(measure).epsilon(1e-12));
  return min_det;
}

std::string write_file(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::temp_directory_path() / ("hypershape_test_" + name);
  std::ofstream(path) << text;
  return path.string();
}

/// The boundary edges of a triangle mesh (edges of exactly one cell).
std::vector<std::pair<int, int>> boundary_edges(const mesh::MeshData& m) {
  std::map<std::pair<int, int>, int> count;
  for (std::int64_t c = 0; c < m.n_cells(); ++c)
    for (int e = 0; e < 3; ++e) {
      int a = m.cells[c * 3 + e], b = m.cells[c * 3 + (e + 1) % 3];
      ++count[{std::min(a, b), std::max(a, b)}];
    }
  std::vector<std::pair<int, int>> out;
  for (auto& [e, n] : count)
    if (n == 1) out.push_back(e);
  return out;
}

/// Number of facets (height-1 points) carrying `label` = 1 on the serial plex.
PetscInt count_marked_facets(DM dm, const char* label) {
  PetscInt f0, f1, n = 0;
  HS_PETSC(DMPlexGetHeightStratum(dm, 1, &f0, &f1));
  DMLabel l;
  HS_PETSC(DMGetLabel(dm, label, &l));
  REQUIRE(l);
  for (PetscInt f = f0; f < f1; ++f) {
    PetscInt v;
    HS_PETSC(DMLabelGetValue(l, f, &v));
    n += v == 1;
  }
  return n;
}

}  // namespace

TEST_CASE("Generated meshes are positively oriented", "[mesh]") {
  constexpr double pi = std::numbers::pi;
  SECTION("disk") {
    mesh::MeshOptions mo;
    mo.h = 0.1;
    check_mesh(mesh::mesh_disk(mo, std::nullopt), 2, pi, 5e-3);
  }
  SECTION("disk with a graded clamp") {
    mesh::MeshOptions mo;
    mo.h = 0.1;
    mo.clamp_size = 0.02;
    check_mesh(mesh::mesh_disk(mo, mesh::ClampRegion{{0.3, -0.7, 0.0}, 0.6}), 2, pi, 5e-3);
  }
  SECTION("ball with a clamp") {
    mesh::MeshOptions mo;
    mo.h = 0.3;
    check_mesh(mesh::mesh_ball(mo, mesh::ClampRegion{{0.0, 0.0, 1.0}, 0.6}), 3, 4.0 / 3.0 * pi,
               0.08);
  }
  SECTION("square") { check_mesh(mesh::mesh_box(2, 2.0, 0.3), 2, 4.0, 1e-12); }
  SECTION("cube") { check_mesh(mesh::mesh_box(3, 1.0, 0.3), 3, 1.0, 1e-12); }
}

TEST_CASE("read_mesh_file orients and compacts and keeps the top-dimensional simplices", "[mesh]") {
  SECTION("triangles (one clockwise), a line element and an orphan node") {
    const std::string path = write_file("square.msh", R"($MeshFormat
2.2 0 8
$EndMeshFormat
$Nodes
6
1 0 0 0
2 1 0 0
3 1 1 0
4 0 1 0
5 5 5 0
6 0.5 0.5 0
$EndNodes
$Elements
6
1 1 2 1 1 1 2
2 2 2 0 1 1 2 6
3 2 2 0 1 2 3 6
4 2 2 0 1 6 3 4
5 2 2 0 1 1 4 6
6 15 2 0 1 5
$EndElements
)");
    const mesh::MeshData m = mesh::read_mesh_file(path);
    CHECK(m.n_vertices() == 5);  // the orphan node 5 is dropped
    CHECK(m.n_cells() == 4);
    check_mesh(m, 2, 1.0, 1e-12);
    std::filesystem::remove(path);
  }
  SECTION("tetrahedra of both orientations") {
    // The unit cube as 6 Kuhn tetrahedra 0 -> x -> y -> z paths; node i at bits (x, y, z) of
    // i - 1. Half are given with odd vertex permutations.
    std::string nodes, elems;
    for (int i = 0; i < 8; ++i)
      nodes += std::to_string(i + 1) + " " + std::to_string(i & 1) + " " +
               std::to_string((i >> 1) & 1) + " " + std::to_string((i >> 2) & 1) + "\n";
    const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    for (int t = 0; t < 6; ++t) {
      int v[4] = {0, 0, 0, 7};
      v[1] = 1 << perms[t][0];
      v[2] = v[1] | (1 << perms[t][1]);
      if (t % 2) std::swap(v[1], v[2]);
      elems += std::to_string(t + 1) + " 4 2 0 1";
      for (int a : v) elems += " " + std::to_string(a + 1);
      elems += "\n";
    }
    const std::string path =
        write_file("cube.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n8\n" + nodes +
                                   "$EndNodes\n$Elements\n6\n" + elems + "$EndElements\n");
    const mesh::MeshData m = mesh::read_mesh_file(path);
    CHECK(m.n_vertices() == 8);
    CHECK(m.n_cells() == 6);
    check_mesh(m, 3, 1.0, 1e-12);
    std::filesystem::remove(path);
  }
}

TEST_CASE("read_mesh_file reads gmsh's own files: MSH 2.2 and 4.1 in ASCII and binary", "[mesh]") {
  // PETSc's data files (package libpetsc3.18-dev-examples, a dependency of this project).
  const std::string dir = "/usr/share/petsc/3.18/share/petsc/datafiles/meshes/";
  struct File {
    const char* name;
    int dim;
  };
  for (const File f :
       {File{"square.msh", 2}, File{"square_bin.msh", 2}, File{"doublet-tet.msh", 3},
        File{"hybrid_triquad.msh", 2}, File{"gmsh-tet.msh", 3}, File{"gmsh-3d-ascii-64.msh", 3},
        File{"gmsh-3d-binary-64.msh", 3}, File{"mesh-3d-box-innersphere.msh", 3}}) {
    DYNAMIC_SECTION(f.name) {
      const std::string path = dir + f.name;
      REQUIRE(std::filesystem::exists(path));
      const mesh::MeshData m = mesh::read_mesh_file(path);
      check_mesh(m, f.dim, -1.0, 0.0);
    }
  }
}

TEST_CASE("Bad mesh input is an InputError", "[mesh]") {
  SECTION("a clockwise triangle") {
    mesh::MeshData m;
    m.dim = 2;
    m.coords = {0, 0, 1, 0, 1, 1, 0, 1};
    m.cells = {0, 1, 2, 0, 3, 2};  // the second is clockwise
    CHECK_THROWS_AS(mesh::create_plex(PETSC_COMM_WORLD, m), core::InputError);
    m.cells = {0, 1, 2, 0, 2, 3};  // fixed
    CHECK_NOTHROW(mesh::create_plex(PETSC_COMM_WORLD, m));
  }
  SECTION("a degenerate triangle") {
    mesh::MeshData m;
    m.dim = 2;
    m.coords = {0, 0, 1, 0, 2, 0, 0, 1};
    m.cells = {0, 1, 3, 0, 1, 2};
    CHECK_THROWS_AS(mesh::create_plex(PETSC_COMM_WORLD, m), core::InputError);
  }
  SECTION("a tetrahedron in gmsh's (right-handed) orientation") {
    mesh::MeshData m;
    m.dim = 3;
    m.coords = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    m.cells = {0, 1, 2, 3};
    CHECK_THROWS_AS(mesh::create_plex(PETSC_COMM_WORLD, m), core::InputError);
    m.cells = {0, 2, 1, 3};
    CHECK_NOTHROW(mesh::create_plex(PETSC_COMM_WORLD, m));
  }
  SECTION("the message says what is wrong") {
    mesh::MeshData m;
    m.dim = 2;
    m.coords = {0, 0, 1, 0, 1, 1, 0, 1};
    m.cells = {0, 2, 1, 0, 3, 2};
    try {
      mesh::create_plex(PETSC_COMM_WORLD, m);
      FAIL("no exception");
    } catch (const core::InputError& e) {
      CHECK_THAT(e.what(), Catch::Contains("2 cells"));
    }
  }
  SECTION("a missing mesh file") {
    const std::string path = "/nonexistent/dir/no_such_mesh.msh";
    try {
      mesh::read_mesh_file(path);
      FAIL("no exception");
    } catch (const core::InputError& e) {
      CHECK(e.file() == path);
      CHECK_THAT(e.what(), Catch::Contains(path));
    }
  }
  SECTION("a file with no triangles or tetrahedra") {
    const std::string path = write_file("lines.msh", R"($MeshFormat
2.2 0 8
$EndMeshFormat
$Nodes
3
1 0 0 0
2 1 0 0
3 2 0 0
$EndNodes
$Elements
2
1 1 2 1 1 1 2
2 1 2 1 1 2 3
$EndElements
)");
    try {
      mesh::read_mesh_file(path);
      FAIL("no exception");
    } catch (const core::InputError& e) {
      CHECK(e.file() == path);
    }
    std::filesystem::remove(path);
  }
}

TEST_CASE("The disk mesh has vertices exactly at the clamp ends", "[mesh]") {
  constexpr double pi = std::numbers::pi;
  struct Clamp {
    double cx, cy, r;
  };
  for (const Clamp cl : {Clamp{1.0, 0.0, 0.5}, Clamp{0.6, 0.8, 0.7}, Clamp{-0.3, -0.9, 0.25}}) {
    DYNAMIC_SECTION("center (" << cl.cx << ", " << cl.cy << "), r " << cl.r) {
      mesh::MeshOptions mo;
      mo.h = 0.05;
      mo.clamp_size = 0.01;
      const mesh::ClampRegion region{{cl.cx, cl.cy, 0.0}, cl.r};
      const mesh::MeshData m = mesh::mesh_disk(mo, region);
      // The clamp ends in closed form: on the circle with x . c = (1 + |c|^2 - r^2) / 2.
      const double cn = std::hypot(cl.cx, cl.cy), phi = std::atan2(cl.cy, cl.cx);
      const double delta = std::acos((1 + cn * cn - cl.r * cl.r) / (2 * cn));
      const double ends[2][2] = {{std::cos(phi - delta), std::sin(phi - delta)},
                                 {std::cos(phi + delta), std::sin(phi + delta)}};
      const auto bedges = boundary_edges(m);
      std::set<int> bverts;
      for (auto [a, b] : bedges) bverts.insert({a, b});
      int n_at_end[2] = {0, 0}, n_on_patch_circle = 0;
      double max_radius_error = 0;
      for (int v : bverts) {
        const double x = m.coords[2 * v], y = m.coords[2 * v + 1];
        max_radius_error = std::max(max_radius_error, std::abs(std::hypot(x, y) - 1.0));
        if (std::abs(std::hypot(x - cl.cx, y - cl.cy) - cl.r) <= 1e-12) ++n_on_patch_circle;
        for (int e = 0; e < 2; ++e)
          if (std::hypot(x - ends[e][0], y - ends[e][1]) <= 1e-12) ++n_at_end[e];
      }
      CHECK(max_radius_error <= 1e-12);  // boundary vertices lie on the unit circle
      CHECK(n_at_end[0] == 1);
      CHECK(n_at_end[1] == 1);
      CHECK(n_on_patch_circle == 2);  // and exactly two at distance r from p_D

      // Facets between the ends (by the angle of their midpoint, independent of the library's
      // distance test) are exactly the ones make_dirichlet_patch marks.
      int n_between = 0;
      double clamped_length = 0;
      for (auto [a, b] : bedges) {
        const double mx = 0.5 * (m.coords[2 * a] + m.coords[2 * b]);
        const double my = 0.5 * (m.coords[2 * a + 1] + m.coords[2 * b + 1]);
        const double dtheta = std::remainder(std::atan2(my, mx) - phi, 2 * pi);
        if (std::abs(dtheta) < delta) {
          ++n_between;
          clamped_length += std::hypot(m.coords[2 * a] - m.coords[2 * b],
                                       m.coords[2 * a + 1] - m.coords[2 * b + 1]);
        }
      }
      REQUIRE(n_between > 3);
      core::DMH dm = mesh::create_plex(PETSC_COMM_WORLD, m);
      auto patch = physics::make_dirichlet_patch({cl.cx, cl.cy}, cl.r);
      patch->mark(dm);
      CHECK(count_marked_facets(dm, "dirichlet_patch") == n_between);
      // The clamped length is the arc length 2 delta up to the chord error.
      CHECK(clamped_length == Approx(2 * delta).epsilon(2e-4));
    }
  }
}

TEST_CASE("The ball mesh has vertices on the clamp circle", "[mesh]") {
  mesh::MeshOptions mo;
  mo.h = 0.25;
  const mesh::ClampRegion region{{0.0, 0.0, 1.0}, 0.6};
  const mesh::MeshData m = mesh::mesh_ball(mo, region);
  // The sphere meets |x - c| = r on the plane z = k, k = (1 + 1 - r^2) / 2.
  const double k = (2.0 - 0.36) / 2.0;
  int n_on_circle = 0;
  for (std::int64_t v = 0; v < m.n_vertices(); ++v) {
    const double* x = &m.coords[std::size_t(v) * 3];
    if (std::abs(std::hypot(x[0], x[1], x[2] - 1.0) - 0.6) <= 1e-12 &&
        std::abs(std::hypot(x[0], x[1], x[2]) - 1.0) <= 1e-12)
      ++n_on_circle;
  }
  // The circle has circumference 2 pi sqrt(1 - k^2) ~ 3.6: at least ~ 3.6 / 0.25 vertices.
  CHECK(n_on_circle >= 12);
  // The patch marks exactly the boundary facets above the circle (by centroid, independent of
  // the library's distance test), whose area is the spherical cap's 2 pi (1 - k) less the
  // inscribed-polyhedron error.
  core::DMH dm = mesh::create_plex(PETSC_COMM_WORLD, m);
  auto patch = physics::make_dirichlet_patch({0.0, 0.0, 1.0}, 0.6);
  patch->mark(dm);
  PetscInt f0, f1;
  HS_PETSC(DMPlexGetHeightStratum(dm, 1, &f0, &f1));
  DMLabel l, bd;
  HS_PETSC(DMGetLabel(dm, "dirichlet_patch", &l));
  HS_PETSC(DMGetLabel(dm, mesh::boundary_label, &bd));
  double area = 0, boundary_area = 0;
  int n_marked = 0, n_above = 0;
  for (PetscInt f = f0; f < f1; ++f) {
    PetscInt on_boundary, marked;
    HS_PETSC(DMLabelGetValue(bd, f, &on_boundary));
    HS_PETSC(DMLabelGetValue(l, f, &marked));
    if (marked == 1) CHECK(on_boundary == 1);
    if (on_boundary != 1) continue;
    PetscReal vol, centroid[3], normal[3];
    HS_PETSC(DMPlexComputeCellGeometryFVM(dm, f, &vol, centroid, normal));
    boundary_area += vol;
    n_above += centroid[2] > k;
    if (marked == 1) {
      ++n_marked;
      area += vol;
    }
  }
  CHECK(n_marked == n_above);
  const double cap = 2.0 * std::numbers::pi * (1.0 - k);
  INFO("clamped area " << area << ", cap " << cap << ", boundary " << boundary_area);
  CHECK(area < cap);
  CHECK(area > 0.95 * cap);  // 15-gon cap boundary: ~3% below the smooth cap at h = 0.25
  CHECK(boundary_area < 4 * std::numbers::pi);
  CHECK(boundary_area > 0.97 * 4 * std::numbers::pi);
}

TEST_CASE("make_dirichlet that selects nothing is an InputError", "[mesh]") {
  std::vector<physics::EffectPtr> effects;
  effects.push_back(physics::make_neo_hookean(500.0, 0.3));
  effects.push_back(physics::make_dirichlet("nowhere", hstest::on_plane(0, 7.0)));
  CHECK_THROWS_AS(physics::Problem(PETSC_COMM_WORLD, mesh::mesh_box(2, 1.0, 0.5),
                                   std::move(effects), hstest::degree(1)),
                  core::InputError);
}
