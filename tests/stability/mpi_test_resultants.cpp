/// Problem::resultants on a distributed mesh: each cell and Neumann facet is summed on one rank
/// only (a ghost counted twice would break the balance), and the totals do not depend on the
/// number of ranks. The distributed scene is compared with the same scene on rank 0 alone
/// (PETSC_COMM_SELF); the totals are reduced, so every rank asserts the same thing.
#include <catch2/catch.hpp>
#include <cmath>

#include "hypershape/solver/nonlinear.hpp"
#include "support/helpers.hpp"

using namespace hypershape;

// Named for the unity build (HS_UNITY_BUILD): files of one batch share a scope.
namespace mpi_test_resultants {
namespace {

using Vec3 = std::array<double, 3>;

double norm(const Vec3& v) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

Vec3 combine(const Vec3& a, double s, const Vec3& b) {
  return {a[0] + s * b[0], a[1] + s * b[1], a[2] + s * b[2]};
}

/// Resultants of the disk scene (h 0.08, P2) on `comm`: at u = 0 under the nominal load, and at
/// the state with max|u| = 0.3 under its alpha. Collective over `comm`.
struct Outcome {
  double alpha = 0;
  physics::Resultants at_rest, loaded;
  std::int64_t n_nodes = 0;
};

Outcome run(MPI_Comm comm) {
  mesh::MeshData m;
  if (core::rank(comm) == 0) m = hstest::disk_mesh(0.08);
  physics::Problem p(comm, m, hstest::disk_effects(), hstest::degree(2));
  solver::NonlinearSolver ns(p);
  const auto t = ns.solve_for_target(0.3);
  REQUIRE(t.converged);
  core::VecH zero = p.create_vector();
  return {t.alpha, p.resultants(zero, 1.0), p.resultants(ns.solution(), t.alpha),
          p.space().n_nodes_global()};
}

/// Rank 0's values of `v` on every rank.
Vec3 broadcast(Vec3 v) {
  MPI_Bcast(v.data(), 3, MPI_DOUBLE, 0, PETSC_COMM_WORLD);
  return v;
}

}  // namespace

TEST_CASE("Reaction and load resultants are rank-count independent and balance", "[mpi]") {
  const Outcome world = run(PETSC_COMM_WORLD);
  Outcome self;
  if (core::rank(PETSC_COMM_WORLD) == 0) self = run(PETSC_COMM_SELF);
  const Vec3 self_force = broadcast(self.loaded.applied_force);
  const Vec3 self_reaction = broadcast(self.loaded.reaction_force);
  const Vec3 self_moment = broadcast(self.at_rest.applied_moment);

  const auto& w = world.loaded;
  REQUIRE(w.admissible);
  const double F = norm(w.applied_force), M = norm(w.applied_moment);
  INFO("alpha " << world.alpha << ", |F| " << F << ", |M| " << M);
  // The load's resultant is a sum of the same facet terms in another order.
  CHECK(norm(combine(world.at_rest.applied_moment, -1, self_moment)) <= 1e-12 * norm(self_moment));
  // The tuned alpha differs by the target tolerance between rank counts (1e-3), the force
  // with it.
  CHECK(norm(combine(w.applied_force, -1, self_force)) <= 2e-3 * F);
  CHECK(norm(combine(w.reaction_force, -1, self_reaction)) <= 2e-3 * F);
  // Balance as in the serial stability suite: C = sqrt(n_nodes), rtol 1e-9.
  const double bound = std::sqrt(double(world.n_nodes)) * 1e-9;
  CHECK(norm(combine(w.reaction_force, 1, w.applied_force)) <= bound * F);
  CHECK(norm(combine(w.reaction_moment, 1, w.applied_moment)) <= 1.5 * bound * M);
  // At rest f_int = 0: nothing holds the load (the Gaussian is ~1e-20 at the patch ends).
  CHECK(norm(world.at_rest.reaction_force) <= 1e-12 * norm(world.at_rest.applied_force));
}

namespace {

/// The disk (h 0.1, P1) under the Gaussian traction at alpha 10, on a spring bed (k_n 50,
/// k_t 20) over its left half, clamped on the patch at (1, 0) or, with `clamped` false, held by
/// the springs alone. Solved to rtol 1e-12. Collective over `comm`.
physics::Resultants spring_scene(MPI_Comm comm, bool clamped, std::int64_t& n_nodes) {
  mesh::MeshData m;
  if (core::rank(comm) == 0) m = hstest::disk_mesh(0.1);
  std::vector<physics::EffectPtr> e;
  e.push_back(physics::make_neo_hookean(500, 0.45));
  if (clamped) e.push_back(physics::make_dirichlet_patch({1.0, 0.0}, 0.5));
  e.push_back(physics::make_spring(50.0, 20.0, physics::Region::box({-1, -1}, {0, 1})));
  e.push_back(physics::make_gaussian_traction({-1.0, 0.0}, {0.0, 1.0}, 0.2));
  physics::Problem p(comm, m, std::move(e), hstest::degree(1));
  solver::SolverOptions so;
  so.rtol = 1e-12;
  solver::NonlinearSolver ns(p, so);
  REQUIRE(ns.solve(10.0).converged);
  n_nodes = p.space().n_nodes_global();
  return p.resultants(ns.solution(), 10.0);
}

}  // namespace

TEST_CASE("Spring forces close the force and moment balance on any number of ranks (issue 18)", "[mpi][supports]") {
  for (bool clamped : {true, false})
    DYNAMIC_SECTION((clamped ? "clamped patch + spring bed" : "spring bed alone")) {
      std::int64_t n_nodes = 0, n_self = 0;
      const physics::Resultants w = spring_scene(PETSC_COMM_WORLD, clamped, n_nodes);
      physics::Resultants s;
      if (core::rank(PETSC_COMM_WORLD) == 0) s = spring_scene(PETSC_COMM_SELF, clamped, n_self);
      const Vec3 self_spring = broadcast(s.spring_force);
      REQUIRE(w.admissible);
      const double F = norm(w.applied_force), M = norm(w.applied_moment);
      const Vec3 total = combine(combine(w.reaction_force, 1, w.spring_force), 1, w.applied_force);
      const Vec3 moment = combine(combine(w.reaction_moment, 1, w.spring_moment), 1, w.applied_moment);
      INFO("|F| " << F << ", |spring| " << norm(w.spring_force) << ", |reaction| " << norm(w.reaction_force)
                  << ", force imbalance " << norm(total) / F << ", moment imbalance " << norm(moment) / M);
      // The springs carry a real share (without them the balance is off by that share) ...
      CHECK(norm(w.spring_force) > 0.05 * F);
      CHECK(norm(combine(w.reaction_force, 1, w.applied_force)) > 0.05 * F);
      // ... and with them it closes to the solver's tolerance (rtol 1e-12, summed over nodes).
      const double bound = std::sqrt(double(n_nodes)) * 1e-10;
      CHECK(norm(total) <= bound * F);
      CHECK(norm(moment) <= bound * M);
      if (!clamped) CHECK(norm(w.reaction_force) == 0.0);
      // Same alpha on every rank count: the spring force agrees to the solver's tolerance.
      CHECK(norm(combine(w.spring_force, -1, self_spring)) <= 1e-8 * F);
    }
}

}  // namespace mpi_test_resultants
