/// factory::prolong_p1_to_p2, the start of the P1 rescue (factory/p1_start.hpp): a P1 field of
/// the disk (2D) and the ball (3D), distributed over the ranks, prolonged to P2 on the same mesh
/// is the same function: at the vertices P1's values, at every edge midpoint exactly the mean of
/// its edge's ends. Checked on rank 0 (gathered, canonical order) and broadcast, so every rank
/// asserts the same thing, on 1, 2 and 3 ranks.
#include <catch2/catch.hpp>
#include <array>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "hypershape/factory/p1_start.hpp"
#include "support/helpers.hpp"

using namespace hypershape;

// Named for the unity build (HS_UNITY_BUILD): files of one batch share a scope.
namespace mpi_test_p1_start {
namespace {

/// Whether the P2 field b (canonical order) is the P1 field a prolonged: a's vertex values, and
/// each midpoint of `cells` (P2, VTK order) the mean of its ends, bit for bit.
bool is_prolongation(const std::vector<double>& a, const std::vector<double>& b, const std::vector<std::int64_t>& cells,
                     int dim) {
  if (b.size() <= a.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (b[i] != a[i]) return false;
  const std::vector<std::array<int, 3>> edges =
      dim == 2 ? std::vector<std::array<int, 3>>{{3, 0, 1}, {4, 1, 2}, {5, 2, 0}}
               : std::vector<std::array<int, 3>>{{4, 0, 1}, {5, 1, 2}, {6, 2, 0}, {7, 0, 3}, {8, 1, 3}, {9, 2, 3}};
  const std::size_t per_cell = dim == 2 ? 6 : 10;
  for (std::size_t c = 0; c + per_cell <= cells.size(); c += per_cell)
    for (const auto& e : edges)
      for (int k = 0; k < dim; ++k) {
        auto at = [&](int n) { return b[std::size_t(cells[c + std::size_t(n)] * dim + k)]; };
        if (at(e[0]) != 0.5 * (at(e[1]) + at(e[2]))) return false;
      }
  return true;
}

}  // namespace

TEST_CASE("A P1 field prolonged to P2 on the same mesh is the same function, on any number of ranks", "[factory]") {
  for (const int dim : {2, 3}) {
    INFO(dim << "D");
    const auto mesh = dim == 2 ? hstest::disk_mesh(0.15) : hstest::ball_mesh(0.45);
    physics::Problem p1{PETSC_COMM_WORLD, mesh, dim == 2 ? hstest::disk_effects() : hstest::ball_effects(),
                        hstest::degree(1)};
    physics::Problem p2{PETSC_COMM_WORLD, mesh, dim == 2 ? hstest::disk_effects() : hstest::ball_effects(),
                        hstest::degree(2)};
    core::VecH u1 = p1.create_vector();
    hstest::interpolate(p1, [](const double* x, double* u) {
      u[0] = std::sin(3 * x[0]) * x[1] + 0.1;
      u[1] = std::cos(2 * x[1]) - x[0] * x[2];
      u[2] = x[0] * x[1] * x[2];
    }, u1);
    const core::VecH u2 = factory::prolong_p1_to_p2(p1, u1, p2);
    const physics::NodalField a = p1.gather(u1), b = p2.gather(u2);
    double ok = 0, nonzero = 0;
    if (core::rank(PETSC_COMM_WORLD) == 0) {
      ok = is_prolongation(a.values, b.values, p2.space().canonical_cells(), dim) ? 1 : 0;
      for (double v : b.values) nonzero += v != 0;
    }
    CHECK(hstest::broadcast(ok) == 1);
    CHECK(hstest::broadcast(nonzero) > 100);  // not a field of zeros
  }
  // P1 to P2 only.
  physics::Problem p{PETSC_COMM_WORLD, hstest::disk_mesh(0.3), hstest::disk_effects(), hstest::degree(1)};
  core::VecH u = p.create_vector();
  CHECK_THROWS_AS(factory::prolong_p1_to_p2(p, u, p), std::logic_error);
}

}  // namespace mpi_test_p1_start
