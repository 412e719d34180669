/// LocalRelaxation (nonlinear elimination before the corrector's global step) and the cell
/// subsets it assembles on: a node pushed off an equilibrium relaxes back to it on its patch and
/// nothing outside the patch moves; a residual spread over the body is left to the global step;
/// a patch's energy and residual are the body's, cell for cell.
#include <catch2/catch.hpp>
#include <cmath>
#include <vector>

#include "hypershape/core/vec_array.hpp"
#include "hypershape/solver/local_relaxation.hpp"
#include "hypershape/solver/nonlinear.hpp"
#include "support/helpers.hpp"

using namespace hypershape;

namespace test_local_relaxation {  // (unity builds: helper names of its own)
namespace {

core::VecH copy_of(Vec v) {
  core::VecH c;
  HS_PETSC(VecDuplicate(v, c.out()));
  HS_PETSC(VecCopy(v, c));
  return c;
}

double max_abs_diff(Vec a, Vec b) {
  core::VecH d = copy_of(a);
  HS_PETSC(VecAXPY(d, -1.0, b));
  PetscReal m;
  HS_PETSC(VecNorm(d, NORM_INFINITY, &m));
  return m;
}

int entries_changed(Vec a, Vec b) {
  PetscInt size;
  HS_PETSC(VecGetLocalSize(a, &size));
  core::VecArray<const PetscScalar> x(a), y(b);
  int n = 0;
  for (PetscInt i = 0; i < size; ++i) n += x[i] != y[i];
  return n;
}

}  // namespace

TEST_CASE("A cell subset's energy and residual are the body's, cell for cell", "[physics][relaxation]") {
  physics::Problem p{PETSC_COMM_WORLD, hstest::disk_mesh(0.1), hstest::disk_effects(500, 0.49), hstest::degree(2)};
  const physics::Space& sp = p.space();
  std::vector<PetscInt> left, right;
  for (PetscInt c = sp.cell_begin(); c < sp.cell_end(); ++c) {
    double x[3] = {0, 0, 0};
    sp.map_point(c, 0, x);
    (x[0] < 0 ? left : right).push_back(c);
  }
  REQUIRE(!left.empty());
  REQUIRE(!right.empty());
  solver::NonlinearSolver ns(p, {});
  REQUIRE(ns.solve_for_target(0.3).converged);
  const double s = ns.load_factor();
  double all, l, r, load_work;
  REQUIRE(p.energy(ns.solution(), s, all));
  REQUIRE(p.energy(ns.solution(), 0.0, load_work));  // the stored energy alone (no fixed load)
  load_work -= all;
  {
    physics::CellSubset only(sp, left);
    REQUIRE(p.energy(ns.solution(), s, l));
  }
  {
    physics::CellSubset only(sp, right);
    REQUIRE(p.energy(ns.solution(), s, r));
  }
  // Each subset's energy carries the whole load's work once.
  CHECK(l + r + load_work == Approx(all).epsilon(1e-12));
  // With the subset gone, the loops visit every cell again.
  double again;
  REQUIRE(p.energy(ns.solution(), s, again));
  CHECK(again == all);
  CHECK(sp.cells().size() == std::size_t(sp.cell_end() - sp.cell_begin()));
}

TEST_CASE("A cell subset's tangent is the body's at the dofs whose cells all lie in it, whatever the matrix held",
          "[physics][relaxation]") {
  // Under a subset Problem::jacobian zeroes only the entries the subset's cells add to (a
  // patch's steps would otherwise zero the whole matrix each): the rows a patch reads must still
  // be the whole tangent's, bit for bit, from a matrix holding another tangent.
  physics::Problem p{PETSC_COMM_WORLD, hstest::disk_mesh(0.1), hstest::disk_effects(500, 0.49), hstest::degree(2)};
  const physics::Space& sp = p.space();
  std::vector<PetscInt> left;
  std::vector<char> outside(std::size_t(sp.n_dofs_global()), 0);  // a dof of a cell not in the subset
  for (PetscInt c = sp.cell_begin(); c < sp.cell_end(); ++c) {
    double x[3] = {0, 0, 0};
    sp.map_point(c, 0, x);
    if (x[0] < 0) {
      left.push_back(c);
      continue;
    }
    for (int k = 0; k < sp.n_cell_dofs(); ++k)
      if (const PetscInt g = sp.global_dofs(c)[k]; g >= 0) outside[std::size_t(g)] = 1;
  }
  solver::NonlinearSolver ns(p, {});
  REQUIRE(ns.solve_for_target(0.3).converged);
  core::MatH whole = p.create_matrix(), patch = p.create_matrix();
  REQUIRE(p.jacobian(ns.solution(), whole, ns.load_factor()));
  core::VecH u0 = p.create_vector();  // the matrix first holds the tangent at rest
  REQUIRE(p.jacobian(u0, patch, 0.0));
  REQUIRE(p.jacobian(u0, patch, 0.0));  // assembled once: the subset's assembly adds in place
  {
    physics::CellSubset only(sp, left);
    REQUIRE(p.jacobian(ns.solution(), patch, ns.load_factor()));
  }
  int rows = 0, differ = 0, stale = 0;
  for (PetscInt c : left)
    for (int k = 0; k < sp.n_cell_dofs(); ++k) {
      const PetscInt g = sp.global_dofs(c)[k];
      if (g < 0) continue;
      PetscInt n1, n2;
      const PetscInt *c1, *c2;
      const PetscScalar *v1, *v2;
      HS_PETSC(MatGetRow(whole, g, &n1, &c1, &v1));
      HS_PETSC(MatGetRow(patch, g, &n2, &c2, &v2));
      REQUIRE(n1 == n2);
      int d = 0;
      for (PetscInt j = 0; j < n1; ++j) d += c1[j] != c2[j] || v1[j] != v2[j];
      HS_PETSC(MatRestoreRow(patch, g, &n2, &c2, &v2));
      HS_PETSC(MatRestoreRow(whole, g, &n1, &c1, &v1));
      if (outside[std::size_t(g)]) {
        stale += d > 0;  // a row the subset does not own: partial sums, or what it held
      } else {
        ++rows;
        differ += d > 0;
      }
    }
  CHECK(rows > 100);
  CHECK(differ == 0);
  CHECK(stale > 0);
}

TEST_CASE("Local relaxation takes a node pushed off an equilibrium back to it on its patch", "[solver][relaxation]") {
  physics::Problem p{PETSC_COMM_WORLD, hstest::disk_mesh(0.08), hstest::disk_effects(500, 0.49), hstest::degree(2)};
  solver::NonlinearSolver ns(p, {});
  const solver::TargetResult t = ns.solve_for_target(0.3);
  REQUIRE(t.converged);
  const double s = t.alpha;
  core::VecH equilibrium = copy_of(ns.solution()), u = copy_of(ns.solution()), r = p.create_vector(),
             fixed = p.create_vector();
  PetscInt n;
  HS_PETSC(VecGetSize(u, &n));
  const double push = 0.01;  // an eighth of h at a node: a local strain of order 0.25
  {
    core::VecArray<PetscScalar> a(u);
    const PetscInt g = 2 * (n / 4);  // a node's two components (node-major)
    a[g] += push;
    a[g + 1] -= push;
  }
  REQUIRE(p.residual(u, s, r));
  solver::LocalRelaxation relaxation(p);
  const auto res = relaxation.relax(u, s, r, fixed);
  INFO(res.dofs << " dofs, |R| there " << res.before << " -> " << res.after << " in " << res.iterations << " steps");
  REQUIRE(res.relaxed);
  CHECK(res.dofs > 2);
  CHECK(res.dofs <= 400);  // three rings of cells in 2D: 232 dofs here
  CHECK(res.after <= 1e-2 * res.before);
  // Back at the equilibrium (the patch's energy minimum with the rest held there), as near as its
  // residual, a hundredth of the start's, says (1.6e-4 when written)...
  CHECK(max_abs_diff(u, equilibrium) <= 2.5e-2 * push);
  // ... and only the patch's dofs moved.
  CHECK(entries_changed(u, equilibrium) <= res.dofs);

  SECTION("a residual spread over the body is left to the global step") {
    core::VecH v = copy_of(equilibrium);
    HS_PETSC(VecScale(v, 1.05));
    REQUIRE(p.residual(v, s, r));
    core::VecH before = copy_of(v);
    const auto spread = relaxation.relax(v, s, r, fixed);
    CHECK_FALSE(spread.relaxed);
    CHECK(entries_changed(v, before) == 0);
  }
  SECTION("the dofs where `fixed` is not zero stay") {
    core::VecH v = copy_of(equilibrium);
    {
      core::VecArray<PetscScalar> a(v), f(fixed);
      const PetscInt g = 2 * (n / 4);
      a[g] += push;
      f[g] = 1.0;
    }
    const core::VecH before = copy_of(v);
    REQUIRE(p.residual(v, s, r));
    const auto held = relaxation.relax(v, s, r, fixed);
    REQUIRE(held.relaxed);
    core::VecArray<const PetscScalar> a(v), b(before);
    CHECK(a[2 * (n / 4)] == b[2 * (n / 4)]);
  }
}

}  // namespace test_local_relaxation
