/// The mixed-precision factorisation (solver: {factor_precision: single}): MUMPS's single-precision
/// LDL^T with solves refined to double. Its solves reach double precision, its inertia is MUMPS's
/// in double, the nonlinear solver reaches the double factor's equilibrium with it (keeping K(0)
/// in 3D), and the config key is parsed and checked.
#include <catch2/catch.hpp>
#include <cmath>
#include <string>
#include <vector>

#include "hypershape/config/dataset.hpp"
#include "hypershape/core/input_error.hpp"
#include "hypershape/solver/ldlt.hpp"
#include "hypershape/solver/nonlinear.hpp"
#include "support/helpers.hpp"

using namespace hypershape;

namespace {

double relative_residual(Mat A, Vec b, Vec x) {
  core::VecH r;
  HS_PETSC(VecDuplicate(b, r.out()));
  HS_PETSC(MatMult(A, x, r));
  HS_PETSC(VecAXPY(r, -1.0, b));
  PetscReal rn, bn;
  HS_PETSC(VecNorm(r, NORM_2, &rn));
  HS_PETSC(VecNorm(b, NORM_2, &bn));
  return rn / bn;
}

}  // namespace

TEST_CASE("The single-precision LDL^T solves to double precision and counts MUMPS's inertia", "[solver]") {
  // K - sigma I of a 3D P2 tangent (nu 0.49: condition ~1e5, so a single-precision solve alone
  // is good to a few digits), definite and indefinite. One factor, refactorised in place (the
  // analysis once): a stale factor would fail the next shift's comparison.
  physics::Problem p{PETSC_COMM_WORLD, hstest::ball_mesh(0.5), hstest::ball_effects(), hstest::degree(2)};
  core::VecH u = p.create_vector(), x = p.create_vector(), y = p.create_vector();
  core::MatH K = p.create_matrix();
  REQUIRE(p.jacobian(u, K));
  solver::LdltFactor single(p, "", true, true);
  REQUIRE(single.single());
  const double diag_mean = hstest::mean_diagonal(K);
  for (const double shift : {0.0, 0.05, 0.3, 0.0}) {
    core::MatH S;
    HS_PETSC(MatDuplicate(K, MAT_COPY_VALUES, S.out()));
    HS_PETSC(MatShift(S, -shift * diag_mean));
    INFO("shift " << shift << " x mean diagonal");
    REQUIRE(single.factorise(S));
    const int neg = hstest::ldlt_negative_eigenvalues(S, MATSOLVERMUMPS);
    CHECK(single.negative_eigenvalues() == neg);
    if (shift == 0.0) CHECK(neg == 0);
    if (shift == 0.3) CHECK(neg > 0);
    REQUIRE(single.solve(p.load(), x));
    const double res = relative_residual(S, p.load(), x);
    INFO("relative residual " << res);
    CHECK(res <= 1e-10);
    // Inside a preconditioner: one single-precision solve, not refined.
    core::VecH z = p.create_vector();
    REQUIRE(single.precondition(p.load(), z));
    const double res_pc = relative_residual(S, p.load(), z);
    INFO("unrefined relative residual " << res_pc);
    CHECK(res_pc < 1e-2);  // 1.6e-3 on the indefinite shift (condition ~1e5)
    CHECK(res_pc > 1e-12);  // not refined to double
    // Against MUMPS in double on the same matrix.
    core::KSPH dbl;
    HS_PETSC(KSPCreate(PETSC_COMM_WORLD, dbl.out()));
    solver::configure_direct_solver(dbl, PETSC_COMM_WORLD, 3);
    HS_PETSC(KSPSetOperators(dbl, S, S));
    HS_PETSC(KSPSolve(dbl, p.load(), y));
    CHECK(hstest::rel_diff(x, y) < 1e-8);
  }
}

TEST_CASE("factor_precision single reaches the double factor's equilibrium on the ball and keeps K(0)", "[solver]") {
  physics::Problem p{PETSC_COMM_WORLD, hstest::ball_mesh(0.4), hstest::ball_effects(), hstest::degree(2)};
  solver::NonlinearSolver dbl(p, solver::SolverOptions{});
  solver::SolverOptions opt;
  opt.tangent.single_factor = true;
  solver::NonlinearSolver single(p, opt);
  for (const double target : {0.3, 0.2}) {
    dbl.reset();
    single.reset();
    const auto td = dbl.solve_for_target(target);
    const auto ts = single.solve_for_target(target);
    INFO("target " << target << ": alpha " << ts.alpha << " (double " << td.alpha << "), " << ts.newton_iterations
                   << " Newton its (double " << td.newton_iterations << "), factorisations " << ts.linear.numeric_factorizations
                   << " (double " << td.linear.numeric_factorizations << ")");
    REQUIRE(td.converged);
    REQUIRE(ts.converged);
    CHECK(ts.negative_pivots == 0);  // the inertia of the single factor found the state stable
    CHECK(std::abs(ts.alpha / td.alpha - 1.0) < 1e-8);
    CHECK(hstest::rel_diff(single.solution(), dbl.solution()) < 1e-7);
    CHECK(ts.newton_iterations == td.newton_iterations);
    // K(0) is factorised once per problem with single factors, once per load case with double.
    if (target == 0.2) CHECK(ts.linear.numeric_factorizations == td.linear.numeric_factorizations - 1);
  }
}

TEST_CASE("A kept single-precision factor preconditions Newton-Krylov unrefined and reaches the double equilibrium",
          "[solver]") {
  // factor_reuse with single factors (3D): GMRES on the current tangent, preconditioned by the
  // factor of an earlier one. That factor's solve is not refined to its own matrix there (each
  // refinement step a product and a back-solve more, for digits of a matrix GMRES is not solving:
  // measured on Random3D, 2.1x the CPU of the load cases); the equilibrium is the double factor's.
  HS_PETSC(PetscLogDefaultBegin());
  physics::Problem p{PETSC_COMM_WORLD, hstest::ball_mesh(0.4), hstest::ball_effects(), hstest::degree(2)};
  solver::NonlinearSolver dbl(p, solver::SolverOptions{});
  solver::SolverOptions opt;
  opt.tangent.single_factor = true;
  opt.tangent.reuse = true;
  solver::NonlinearSolver kept(p, opt);
  const auto td = dbl.solve_for_target(0.3);
  const double products0 = hstest::event_count("MatMult"), orthog0 = hstest::event_count("KSPGMRESOrthog");
  const auto tk = kept.solve_for_target(0.3);
  const double products = hstest::event_count("MatMult") - products0;
  const double gmres = hstest::event_count("KSPGMRESOrthog") - orthog0;
  INFO("alpha " << tk.alpha << " (double " << td.alpha << "); factorisations " << tk.linear.numeric_factorizations
                << " (double " << td.linear.numeric_factorizations << "), Krylov its " << tk.linear.krylov_iterations
                << ", products "
                << products << ", GMRES orthogonalisations " << gmres);
  REQUIRE(td.converged);
  REQUIRE(tk.converged);
  CHECK(tk.negative_pivots == 0);
  CHECK(std::abs(tk.alpha / td.alpha - 1.0) < 1e-7);
  CHECK(hstest::rel_diff(kept.solution(), dbl.solution()) < 1e-6);
  CHECK(tk.linear.numeric_factorizations < td.linear.numeric_factorizations);
  REQUIRE(tk.linear.krylov_iterations > 0);
  // One product with the tangent per GMRES iteration and one per Krylov solve (its true residual);
  // a refined preconditioner adds at least one more per iteration, against the factor's matrix.
  CHECK(products < 1.5 * tk.linear.krylov_iterations + 2 * tk.newton_iterations + 10);
}

TEST_CASE("solver.factor_precision is parsed, joins the identity only when single, and a bad value is refused",
          "[solver][config]") {
  const auto c = config::parse_dataset_text("preset: random2d\nsolver: {factor_precision: single}\n", "<test>");
  CHECK(c.solver.tangent.single_factor);
  const auto d = config::parse_dataset_text("preset: random2d\nsolver: {factor_precision: double}\n", "<test>");
  CHECK_FALSE(d.solver.tangent.single_factor);
  const auto preset = config::parse_dataset_text("preset: random2d\n", "<test>");
  CHECK(config::canonical_text(d) == config::canonical_text(preset));
  CHECK(config::canonical_text(c) != config::canonical_text(preset));
  try {
    (void)config::parse_dataset_text("preset: random2d\nsolver: {factor_precision: half}\n", "<test>");
    FAIL("no error");
  } catch (const core::InputError& e) {
    CHECK(e.key() == "solver.factor_precision");
    CHECK(std::string(e.what()).find("double or single") != std::string::npos);
  }
}
