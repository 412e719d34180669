/// Results do not depend on the number of ranks: the disk scene solved on PETSC_COMM_WORLD
/// (METIS-distributed) against the same scene solved on rank 0 alone (PETSC_COMM_SELF). Every
/// comparison is made on rank 0 and broadcast, so all ranks assert the same thing.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>

#include "hypershape/solver/nonlinear.hpp"
#include "support/helpers.hpp"

using namespace hypershape;

// Named for the unity build (HS_UNITY_BUILD): files of one batch share a scope.
namespace mpi_test_ranks {
namespace {

constexpr double h = 0.08;

int world_rank() { return core::rank(PETSC_COMM_WORLD); }

using hstest::broadcast;

/// max_i |a_i - b_i| / max_i |b_i| (rank 0's arrays).
double rel_max_diff(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.size() != b.size() || b.empty()) return INFINITY;
  double d = 0, m = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    d = std::max(d, std::abs(a[i] - b[i]));
    m = std::max(m, std::abs(b[i]));
  }
  return m > 0 ? d / m : INFINITY;
}

struct Outcome {
  bool converged = false;
  double alpha = 0, max_u = 0, min_det = 0;
  physics::NodalField u;
};

/// Builds the scene on `comm` (mesh read on its rank 0) and solves it: at `alpha` if positive,
/// else for the target max|u| = -alpha. Collective over `comm`.
Outcome run(MPI_Comm comm, int degree, double alpha) {
  mesh::MeshData m;
  if (core::rank(comm) == 0) m = hstest::disk_mesh(h);
  physics::Problem p(comm, m, hstest::disk_effects(), hstest::degree(degree));
  solver::NonlinearSolver ns(p);
  Outcome o;
  if (alpha > 0) {
    const auto r = ns.solve(alpha);
    o.converged = r.converged;
    o.alpha = alpha;
    o.max_u = r.max_displacement;
  } else {
    const auto t = ns.solve_for_target(-alpha);
    o.converged = t.converged;
    o.alpha = t.alpha;
    o.max_u = t.max_displacement;
  }
  o.min_det = p.min_det_f(ns.solution());
  o.u = p.gather(ns.solution());
  return o;
}

}  // namespace

TEST_CASE("Parallel assembly equals serial assembly", "[mpi]") {
  for (int degree : {1, 2}) {
    DYNAMIC_SECTION("P" << degree) {
      // Smooth, zero on the clamped patch |x - (1, 0)| <= 0.5.
      auto field = [](const double* x, double* v) {
        const double phi = std::max(0.0, (x[0] - 1) * (x[0] - 1) + x[1] * x[1] - 0.25) / 3.0;
        v[0] = phi * 0.3 * std::sin(x[0] + 2 * x[1]);
        v[1] = phi * (0.25 * std::cos(1.5 * x[0] - x[1]) - 0.15 * x[0] * x[0]);
      };
      // Serial reference on rank 0: energy and the residual at the nodes (canonical order).
      double e_ref = 0;
      physics::NodalField r_ref;
      if (world_rank() == 0) {
        physics::Problem p(PETSC_COMM_SELF, hstest::disk_mesh(h), hstest::disk_effects(),
                           hstest::degree(degree));
        core::VecH u = p.create_vector(), r = p.create_vector();
        hstest::interpolate(p, field, u);
        REQUIRE(p.energy(u, 3.0, e_ref));  // rank 0 alone: no other rank waits here
        REQUIRE(p.residual(u, 3.0, r));
        r_ref = p.gather(r);
      }
      mesh::MeshData m;
      if (world_rank() == 0) m = hstest::disk_mesh(h);
      physics::Problem p(PETSC_COMM_WORLD, m, hstest::disk_effects(), hstest::degree(degree));
      core::VecH u = p.create_vector(), r = p.create_vector();
      hstest::interpolate(p, field, u);
      double e = 0;
      const bool ok_e = p.energy(u, 3.0, e);
      const bool ok_r = p.residual(u, 3.0, r);
      const physics::NodalField rg = p.gather(r);
      const double de = broadcast(world_rank() == 0 ? std::abs(e - e_ref) / std::abs(e_ref) : 0.0);
      const double dr = broadcast(world_rank() == 0 ? rel_max_diff(rg.values, r_ref.values) : 0.0);
      INFO("ranks " << core::size(PETSC_COMM_WORLD) << ": energy diff " << de << ", residual diff "
                    << dr);
      CHECK(ok_e);
      CHECK(ok_r);
      double r_max = 0;
      for (double v : r_ref.values) r_max = std::max(r_max, std::abs(v));
      CHECK(broadcast(r_max) > 1.0);  // a loaded, deformed state: the residual is far from zero
      CHECK(de < 1e-12);
      CHECK(dr < 1e-12);
      CHECK(p.space().n_cells_global() > 100);
    }
  }
}

TEST_CASE("The disk scene has the same solution on any number of ranks", "[mpi]") {
  for (int degree : {1, 2}) {
    DYNAMIC_SECTION("P" << degree) {
      // alpha > 0: a fixed load; alpha < 0: the target search for max|u| = 0.3.
      for (double alpha : {20.0, -0.3}) {
        Outcome ref;
        if (world_rank() == 0) ref = run(PETSC_COMM_SELF, degree, alpha);
        const Outcome par = run(PETSC_COMM_WORLD, degree, alpha);
        const double ref_ok = broadcast(ref.converged ? 1.0 : 0.0);
        const double du =
            broadcast(world_rank() == 0 ? rel_max_diff(par.u.values, ref.u.values) : 0.0);
        const double dalpha =
            broadcast(world_rank() == 0 ? std::abs(par.alpha - ref.alpha) / ref.alpha : 0.0);
        const double dmax =
            broadcast(world_rank() == 0 ? std::abs(par.max_u - ref.max_u) / ref.max_u : 0.0);
        INFO("ranks " << core::size(PETSC_COMM_WORLD) << ", alpha " << alpha
                      << ": relative differences u " << du << ", alpha " << dalpha << ", max|u| "
                      << dmax);
        CHECK(ref_ok == 1.0);
        CHECK(par.converged);
        CHECK(par.min_det > 0);
        CHECK(du < 1e-8);
        CHECK(dalpha < 1e-8);
        CHECK(dmax < 1e-8);
        if (alpha < 0) CHECK(std::abs(par.max_u / 0.3 - 1.0) <= 1e-3);
      }
    }
  }
}

TEST_CASE("Where a mode lives is the same on any number of ranks", "[mpi]") {
  // A bump around (-0.1, 0.1), wide enough (its tenth at r = 0.64) to lie on every rank's part
  // of the disk: the count is summed over ranks, the peak is one node.
  auto bump = [](const double* x, double* v) {
    const double r2 = (x[0] + 0.1) * (x[0] + 0.1) + (x[1] - 0.1) * (x[1] - 0.1);
    v[0] = std::exp(-r2 / (2 * 0.3 * 0.3));
    v[1] = 0.5 * v[0];
  };
  for (int degree : {1, 2}) {
    DYNAMIC_SECTION("P" << degree) {
      solver::ModeExtent ref;
      if (world_rank() == 0) {
        physics::Problem p(PETSC_COMM_SELF, hstest::disk_mesh(h), hstest::disk_effects(), hstest::degree(degree));
        core::VecH v = p.create_vector();
        hstest::interpolate(p, bump, v);
        ref = solver::mode_extent(p, v);
      }
      mesh::MeshData m;
      if (world_rank() == 0) m = hstest::disk_mesh(h);
      physics::Problem p(PETSC_COMM_WORLD, m, hstest::disk_effects(), hstest::degree(degree));
      core::VecH v = p.create_vector();
      hstest::interpolate(p, bump, v);
      const solver::ModeExtent par = solver::mode_extent(p, v);
      const double same = broadcast(world_rank() == 0 ? double(par.nodes == ref.nodes && par.at == ref.at) : 0.0);
      const double nodes = broadcast(world_rank() == 0 ? double(ref.nodes) : 0.0);
      const double dist = broadcast(world_rank() == 0 ? std::hypot(ref.at[0] + 0.1, ref.at[1] - 0.1) : 0.0);
      INFO("ranks " << core::size(PETSC_COMM_WORLD) << ": " << par.nodes << " nodes at (" << par.at[0] << ", "
                    << par.at[1] << ")");
      CHECK(same == 1.0);
      CHECK(nodes > 10);   // a patch, not one node
      CHECK(dist < h);     // the peak is the node next to the bump's centre
    }
  }
}

}  // namespace mpi_test_ranks
