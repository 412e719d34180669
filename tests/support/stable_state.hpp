#pragma once
/// The contract of a converged target solve, checked independently of the solver (Catch
/// assertions): equilibrium by the true residual, max|u| on target, det F > 0, finite values,
/// and a positive definite tangent (a fresh MUMPS LDL^T of the Jacobian has no negative pivot).
#include <catch2/catch.hpp>

#include <cmath>

#include "support/helpers.hpp"

namespace hstest {

inline void check_stable_on_target(const hs::physics::Problem& p, Vec u, const hs::solver::TargetResult& r,
                                   double target, const hs::solver::SolverOptions& opt) {
  REQUIRE(r.converged);
  CHECK(std::abs(r.max_displacement / target - 1) <= opt.target_rtol);
  hs::core::VecH res = p.create_vector();
  REQUIRE(p.residual(u, r.alpha, res));
  PetscReal rn;
  HS_PETSC(VecNorm(res, NORM_2, &rn));
  CHECK(rn <= opt.rtol * std::abs(r.alpha) * p.load_norm() + opt.atol);
  CHECK(p.min_det_f(u) > 0);
  CHECK(all_finite(values(u)));
  hs::core::MatH K = p.create_matrix();
  REQUIRE(p.jacobian(u, K));
  CHECK(ldlt_negative_eigenvalues(K, MATSOLVERMUMPS) == 0);
}

}  // namespace hstest
