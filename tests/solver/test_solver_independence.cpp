/// Several NonlinearSolvers may exist for one Problem at the same time (a guarded and an
/// unguarded one, one per load family, a reference solve in a test): each must solve its own
/// load. (Kept in its own file so that CTest reports it separately.)
#include <catch2/catch.hpp>

#include "hypershape/solver/nonlinear.hpp"
#include "support/helpers.hpp"

using namespace hypershape;

TEST_CASE("Two solvers of one problem solve their own loads", "[solver]") {
  physics::Problem p(PETSC_COMM_WORLD, hstest::disk_mesh(0.1), hstest::disk_effects(),
                     hstest::degree(1));
  // Reference: one solver alive at a time.
  double m10, m25;
  {
    solver::NonlinearSolver ns(p);
    const auto r = ns.solve(10.0);
    REQUIRE(r.converged);
    m10 = r.max_displacement;
    REQUIRE(ns.solve(25.0).converged);
    m25 = p.max_displacement(ns.solution());
  }
  REQUIRE(m10 > 0.1);
  solver::NonlinearSolver a(p), b(p);
  const auto ra = a.solve(10.0);
  const auto rb = b.solve(25.0);
  INFO("a: " << ra.reason << " after " << ra.newton_iterations
             << " Newton iterations; b: " << rb.reason << " after " << rb.newton_iterations);
  CHECK(ra.converged);
  CHECK(rb.converged);
  CHECK(p.max_displacement(a.solution()) == Approx(m10).epsilon(1e-7));
  CHECK(p.max_displacement(b.solution()) == Approx(m25).epsilon(1e-7));
}
