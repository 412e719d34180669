/// The assembled tangent against finite-difference Jacobians of the residual at a non-trivial
/// (converged, loaded) state: our own central differences of Problem::residual, column by
/// column, and PETSc's SNESComputeJacobianDefault through the solver's SNES callbacks.
#include <Eigen/Dense>
#include <catch2/catch.hpp>
#include <cmath>

#include "hypershape/solver/nonlinear.hpp"
#include "support/helpers.hpp"

using namespace hypershape;

namespace {

Eigen::MatrixXd dense(Mat A) {
  PetscInt m, n;
  HS_PETSC(MatGetSize(A, &m, &n));
  Eigen::MatrixXd D = Eigen::MatrixXd::Zero(m, n);
  for (PetscInt i = 0; i < m; ++i) {
    PetscInt nc;
    const PetscInt* cols;
    const PetscScalar* vals;
    HS_PETSC(MatGetRow(A, i, &nc, &cols, &vals));
    for (PetscInt k = 0; k < nc; ++k) D(i, cols[k]) = PetscRealPart(vals[k]);
    HS_PETSC(MatRestoreRow(A, i, &nc, &cols, &vals));
  }
  return D;
}

std::unique_ptr<physics::Problem> make_problem(int dim, int degree) {
  std::vector<physics::EffectPtr> effects;
  effects.push_back(physics::make_neo_hookean(500.0, 0.45));
  mesh::MeshData m;
  if (dim == 2) {
    m = hstest::disk_mesh(0.3);
    effects.push_back(physics::make_dirichlet_patch({1.0, 0.0}, 0.5));
    effects.push_back(physics::make_gaussian_traction({-1.0, 0.0}, {0.0, 1.0}, 0.2));
  } else {
    m = mesh::mesh_box(3, 1.0, 0.5);
    effects.push_back(physics::make_dirichlet("clamp", hstest::on_plane(0, 0.0)));
    effects.push_back(physics::make_gaussian_traction({1.0, 1.0, 1.0}, {0.0, 0.0, -1.0}, 0.3));
  }
  return std::make_unique<physics::Problem>(PETSC_COMM_WORLD, m, std::move(effects),
                                            hstest::degree(degree));
}

}  // namespace

TEST_CASE("Assembled tangent equals the finite-difference Jacobian at a loaded state",
          "[jacobian]") {
  struct Case {
    const char* name;
    int dim, degree;
  };
  for (const Case c :
       {Case{"2D P1", 2, 1}, Case{"2D P2", 2, 2}, Case{"3D P1", 3, 1}, Case{"3D P2", 3, 2}}) {
    DYNAMIC_SECTION(c.name) {
      auto p = make_problem(c.dim, c.degree);
      solver::NonlinearSolver ns(*p);
      // A load that deforms the body strongly (max |u| ~ 0.25 of a unit body).
      const auto t = ns.solve_for_target(0.25);
      REQUIRE(t.converged);
      Vec u = ns.solution();
      const double s = ns.load_factor();
      INFO("state: alpha = " << s << ", max|u| = " << t.max_displacement
                             << ", min det F = " << p->min_det_f(u));
      REQUIRE(p->min_det_f(u) > 0);
      REQUIRE(t.max_displacement > 0.2);

      core::MatH J = p->create_matrix();
      REQUIRE(p->jacobian(u, J));
      const Eigen::MatrixXd Ja = dense(J);
      const Eigen::Index n = Ja.rows();
      REQUIRE(n > 20);

      SECTION("own central differences of Problem::residual") {
        core::VecH w = p->create_vector(), rp = p->create_vector(), rm = p->create_vector();
        Eigen::MatrixXd Jfd(n, n);
        const double h = 1e-6;
        for (Eigen::Index j = 0; j < n; ++j) {
          HS_PETSC(VecCopy(u, w));
          HS_PETSC(VecSetValue(w, PetscInt(j), h, ADD_VALUES));
          HS_PETSC(VecAssemblyBegin(w));
          HS_PETSC(VecAssemblyEnd(w));
          REQUIRE(p->residual(w, s, rp));
          HS_PETSC(VecSetValue(w, PetscInt(j), -2.0 * h, ADD_VALUES));
          HS_PETSC(VecAssemblyBegin(w));
          HS_PETSC(VecAssemblyEnd(w));
          REQUIRE(p->residual(w, s, rm));
          const PetscScalar *a, *b;
          HS_PETSC(VecGetArrayRead(rp, &a));
          HS_PETSC(VecGetArrayRead(rm, &b));
          for (Eigen::Index i = 0; i < n; ++i) Jfd(i, j) = (a[i] - b[i]) / (2 * h);
          HS_PETSC(VecRestoreArrayRead(rp, &a));
          HS_PETSC(VecRestoreArrayRead(rm, &b));
        }
        const double rel = (Ja - Jfd).norm() / Ja.norm();
        INFO("n = " << n << ", ||J||_F = " << Ja.norm() << ", relative FD difference " << rel);
        CHECK(rel < 1e-6);
        // And it is not the tangent at the reference state (the state matters).
        core::VecH zero = p->create_vector();
        core::MatH J0 = p->create_matrix();
        REQUIRE(p->jacobian(zero, J0));
        CHECK((dense(J0) - Jfd).norm() / Ja.norm() > 1e-2);
      }

      SECTION("PETSc's SNESComputeJacobianDefault") {
        // The SNES callbacks assemble at the load factor of the last solve.
        core::MatH Jfd;
        HS_PETSC(
            MatCreateDense(PETSC_COMM_WORLD, PETSC_DECIDE, PETSC_DECIDE, n, n, nullptr, Jfd.out()));
        HS_PETSC(SNESComputeJacobianDefault(ns.snes(), u, Jfd, Jfd, nullptr));
        const double rel = (Ja - dense(Jfd)).norm() / Ja.norm();
        INFO("relative difference to PETSc's forward-difference Jacobian " << rel);
        CHECK(rel < 1e-5);
      }
    }
  }
}
