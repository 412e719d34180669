/// The multigrid linear solvers of the tangent (solver: {linear: gamg | hypre}): they reach the
/// direct solver's equilibrium on the ball without a single factorisation, the LOBPCG stability
/// check settles the sign of the smallest eigenvalue that the factor's inertia gave, and the
/// config key is parsed and checked.
#include <catch2/catch.hpp>
#include <cmath>
#include <string>
#include <vector>

#include "hypershape/config/dataset.hpp"
#include "hypershape/core/input_error.hpp"
#include "hypershape/solver/multigrid.hpp"
#include "hypershape/solver/nonlinear.hpp"
#include "support/helpers.hpp"

#include <petscblaslapack.h>

using namespace hypershape;

TEST_CASE("GAMG and BoomerAMG reach the direct solver's equilibrium on the ball, without factorising", "[solver]") {
  physics::Problem p{PETSC_COMM_WORLD, hstest::ball_mesh(0.4), hstest::ball_effects(), hstest::degree(2)};
  solver::SolverOptions direct;
  direct.tangent.linear = solver::LinearSolver::direct;
  solver::NonlinearSolver ref(p, direct);
  const auto t_ref = ref.solve_for_target(0.3);
  REQUIRE(t_ref.converged);
  REQUIRE(t_ref.linear.numeric_factorizations > 0);
  for (auto kind : {solver::LinearSolver::gamg, solver::LinearSolver::hypre}) {
    solver::SolverOptions opt;
    opt.tangent.linear = kind;
    solver::NonlinearSolver ns(p, opt);
    const auto t = ns.solve_for_target(0.3);
    INFO(solver::to_string(kind) << ": " << t.reason << ", alpha " << t.alpha << " (direct " << t_ref.alpha << "), "
                                 << t.newton_iterations << " Newton its, " << t.linear.krylov_iterations << " Krylov its");
    REQUIRE(t.converged);
    CHECK(t.negative_pivots == 0);  // the LOBPCG check found the state stable
    CHECK(t.linear.numeric_factorizations == 0);
    CHECK(t.linear.krylov_iterations > 0);
    // Both converge to ||R|| <= 1e-9 ||alpha f||: the same equilibrium, to that tolerance.
    CHECK(std::abs(t.alpha / t_ref.alpha - 1.0) < 1e-6);
    CHECK(hstest::rel_diff(ns.solution(), ref.solution()) < 1e-6);
  }
}

TEST_CASE("auto picks the multigrid solver in 3D from its size, the direct one below it and in 2D", "[solver]") {
  using solver::LinearSolver;
  CHECK(solver::resolve_linear_solver(LinearSolver::automatic, 3, 200000, 100000) == LinearSolver::gamg);
  CHECK(solver::resolve_linear_solver(LinearSolver::automatic, 3, 5000, 100000) == LinearSolver::direct);
  CHECK(solver::resolve_linear_solver(LinearSolver::automatic, 2, 500000, 100000) == LinearSolver::direct);
  CHECK(solver::resolve_linear_solver(LinearSolver::hypre, 2, 10, 100000) == LinearSolver::hypre);
  for (auto s : {LinearSolver::automatic, LinearSolver::direct, LinearSolver::gamg, LinearSolver::hypre})
    CHECK(solver::linear_solver_from_string(solver::to_string(s)) == s);
  CHECK_FALSE(solver::linear_solver_from_string("amg"));
}

TEST_CASE("LOBPCG preconditioned by GAMG settles the sign of the tangent's smallest eigenvalue", "[solver]") {
  // The ball's tangent at rest (P1, h 0.5: small enough for dense eigenvalues), shifted below,
  // between and above its smallest eigenvalues: the sign the factor's inertia would give.
  physics::Problem p{PETSC_COMM_WORLD, hstest::ball_mesh(0.5), hstest::ball_effects(), hstest::degree(1)};
  core::VecH u = p.create_vector();
  core::MatH K = p.create_matrix();
  REQUIRE(p.jacobian(u, K));
  const auto w = hstest::dense_eigenvalues(K);
  REQUIRE(w[0] > 0);
  solver::set_rigid_body_near_null_space(p, K);
  for (double sigma : {0.5 * w[0], 0.5 * (w[0] + w[1]), 0.5 * (w[2] + w[3])}) {
    core::MatH S;
    HS_PETSC(MatDuplicate(K, MAT_COPY_VALUES, S.out()));
    HS_PETSC(MatShift(S, -sigma));
    core::KSPH ksp = solver::make_multigrid_ksp(PETSC_COMM_WORLD, solver::LinearSolver::gamg, "lobpcg_test_");
    HS_PETSC(KSPSetOperators(ksp, S, S));
    HS_PETSC(KSPSetUp(ksp));
    PC pc;
    HS_PETSC(KSPGetPC(ksp, &pc));
    core::VecH x = p.create_vector();
    HS_PETSC(VecSetRandom(x, nullptr));
    const auto e = solver::smallest_eigenvalue(S, pc, x, 0.1, 300);
    INFO("sigma " << sigma << ": smallest eigenvalue " << w[0] - sigma << ", LOBPCG " << e.value << " (residual "
                  << e.residual << ", " << e.iterations << " its)");
    REQUIRE(e.settled);
    CHECK((e.value < 0) == (w[0] - sigma < 0));
    if (e.value > 0) CHECK(std::abs(e.value - (w[0] - sigma)) <= 0.2 * (w[0] - sigma));
  }
}

TEST_CASE("solver.linear is parsed and a bad value is refused with its key and the allowed values", "[solver][config]") {
  const auto c = config::parse_dataset_text("preset: random3d\nsolver: {linear: hypre, linear_auto_dofs: 5000}\n", "<test>");
  CHECK(c.solver.tangent.linear == solver::LinearSolver::hypre);
  CHECK(c.solver.tangent.auto_dofs == 5000);
  CHECK(config::parse_dataset_text("preset: random3d\n", "<test>").solver.tangent.linear == solver::LinearSolver::automatic);
  auto error_of = [](const std::string& text) {
    try {
      (void)config::parse_dataset_text(text, "<test>");
    } catch (const core::InputError& e) {
      return e.key() + ": " + e.what();
    }
    return std::string("no error");
  };
  const std::string bad = error_of("preset: random3d\nsolver: {linear: amg}\n");
  CHECK(bad.rfind("solver.linear", 0) == 0);
  CHECK(bad.find("auto, direct, gamg or hypre") != std::string::npos);
  CHECK(error_of("preset: random3d\nsolver: {linear: gamg, factor_reuse: true}\n").rfind("solver.factor_reuse", 0) == 0);
  CHECK(error_of("preset: random3d\nsolver: {linear_auto_dofs: 0}\n").rfind("solver.linear_auto_dofs", 0) == 0);
}
