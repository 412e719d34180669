/// Problem::resultants on a distributed mesh: each cell and Neumann facet is summed on one rank
/// only (a ghost counted twice would break the balance), and the totals do not depend on the
/// number of ranks. The distributed scene is compared with the same scene on rank 0 alone
/// (PETSC_COMM_SELF); the totals are reduced, so every rank asserts the same thing.
#include <catch2/catch.hpp>
#include <cmath>

#include "hypershape/solver/nonlinear.hpp"
#include "support/helpers.hpp"

using namespace hypershape;

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
