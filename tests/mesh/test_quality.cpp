/// mesh_quality on hand-made cells with known figures, and the gate.
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>
#include <string>

#include "hypershape/mesh/quality.hpp"

using namespace hypershape;

namespace {

mesh::MeshData cells(int dim, std::vector<double> coords, std::vector<int> cells) {
  mesh::MeshData m;
  m.dim = dim;
  m.coords = std::move(coords);
  m.cells = std::move(cells);
  return m;
}

const double s3 = std::sqrt(3.0);

}  // namespace

TEST_CASE("quality of triangles", "[mesh][quality]") {
  SECTION("equilateral, counter-clockwise") {
    const auto q = mesh::mesh_quality(cells(2, {0, 0, 2, 0, 1, s3}, {0, 1, 2}));
    CHECK(q.min_angle_deg == Approx(60.0).epsilon(1e-12));
    CHECK(q.min_shape == Approx(1.0).epsilon(1e-12));
    CHECK(q.min_edge == Approx(2.0).epsilon(1e-12));
    CHECK(q.max_edge == Approx(2.0).epsilon(1e-12));
    CHECK(q.n_inverted == 0);
    CHECK(q.n_cells == 1);
    CHECK(q.n_vertices == 3);
    CHECK(mesh::passes(q, mesh::QualityGate::defaults(2)));
  }
  SECTION("right isosceles, plus the same clockwise (inverted)") {
    const auto q = mesh::mesh_quality(cells(2, {0, 0, 1, 0, 0, 1}, {0, 1, 2, 0, 2, 1}));
    CHECK(q.min_angle_deg == Approx(45.0).epsilon(1e-12));
    // 4 sqrt(3) (1/2) / (1 + 1 + 2)
    CHECK(q.min_shape == Approx(s3 / 2).epsilon(1e-12));
    CHECK(q.max_edge == Approx(std::sqrt(2.0)).epsilon(1e-12));
    CHECK(q.min_edge == Approx(1.0).epsilon(1e-12));
    CHECK(q.n_inverted == 1);
    std::string why;
    CHECK_FALSE(mesh::passes(q, mesh::QualityGate::defaults(2), &why));
    CHECK(why.find("inverted") != std::string::npos);
  }
  SECTION("a thin triangle fails the gate on its angle") {
    const auto q = mesh::mesh_quality(cells(2, {0, 0, 1, 0, 0.5, 0.05}, {0, 1, 2}));
    CHECK(q.min_angle_deg == Approx(std::atan(0.1) * 180 / std::numbers::pi).epsilon(1e-12));
    std::string why;
    CHECK_FALSE(mesh::passes(q, mesh::QualityGate::defaults(2), &why));
    CHECK(why.find("angle") != std::string::npos);
  }
}

TEST_CASE("quality of tetrahedra", "[mesh][quality]") {
  // Regular tetrahedron (alternate corners of a cube), ordered with a negative triple product:
  // PETSc's positive orientation.
  const std::vector<double> regular = {1, 1, 1, 1, -1, -1, -1, 1, -1, -1, -1, 1};
  SECTION("regular") {
    auto m = cells(3, regular, {0, 1, 2, 3});
    const auto q = mesh::mesh_quality(m);
    CHECK(q.min_angle_deg == Approx(std::acos(1.0 / 3) * 180 / std::numbers::pi).epsilon(1e-12));
    CHECK(q.min_angle_deg == Approx(70.5288).epsilon(1e-5));
    CHECK(q.min_shape == Approx(1.0).epsilon(1e-12));
    CHECK(q.min_edge == Approx(std::sqrt(8.0)).epsilon(1e-12));
    CHECK(q.max_edge == Approx(std::sqrt(8.0)).epsilon(1e-12));
    CHECK(q.n_inverted == 0);
    CHECK(mesh::passes(q, mesh::QualityGate::defaults(3)));
    // The other orientation is inverted for PETSc.
    m.cells = {0, 2, 1, 3};
    CHECK(mesh::mesh_quality(m).n_inverted == 1);
  }
  SECTION("the unit corner tetrahedron") {
    // Radius ratio of the corner tet: r_in = 1/(3+sqrt3), R = sqrt3/2.
    const auto q = mesh::mesh_quality(cells(3, {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1}, {0, 2, 1, 3}));
    CHECK(q.min_shape == Approx(3.0 / (3 + s3) / (s3 / 2)).epsilon(1e-12));
    CHECK(q.min_angle_deg == Approx(std::acos(1 / s3) * 180 / std::numbers::pi).epsilon(1e-12));
    CHECK(q.n_inverted == 0);
  }
  SECTION("a sliver: four nearly coplanar points on a circle") {
    // Square corners with two opposite ones lifted/lowered by eps: good edges, ~zero volume.
    const double eps = 0.01;
    const auto q = mesh::mesh_quality(
        cells(3, {1, 0, eps, 0, 1, -eps, -1, 0, eps, 0, -1, -eps}, {0, 1, 2, 3}));
    const auto q2 = mesh::mesh_quality(
        cells(3, {1, 0, eps, 0, 1, -eps, -1, 0, eps, 0, -1, -eps}, {0, 2, 1, 3}));
    CHECK(q.min_shape < 0.05);
    CHECK(q.min_angle_deg < 3.0);
    CHECK(q.min_edge > 1.0);  // no short edge: edge-length checks would miss it
    CHECK(q.n_inverted + q2.n_inverted == 1);
    std::string why;
    const auto& good = q.n_inverted == 0 ? q : q2;
    CHECK_FALSE(mesh::passes(good, mesh::QualityGate::defaults(3), &why));
    CHECK(why.find("angle") != std::string::npos);
  }
  SECTION("a flat tetrahedron counts as inverted") {
    const auto q = mesh::mesh_quality(cells(3, {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0}, {0, 1, 2, 3}));
    CHECK(q.n_inverted == 1);
    CHECK(q.min_shape == 0.0);
  }
}

TEST_CASE("an empty mesh does not pass", "[mesh][quality]") {
  const auto q = mesh::mesh_quality(mesh::MeshData{});
  CHECK(q.n_cells == 0);
  std::string why;
  CHECK_FALSE(mesh::passes(q, mesh::QualityGate{}, &why));
  CHECK(why == "no cells");
}
