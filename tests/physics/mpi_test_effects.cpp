/// The catalogue's effects give the same solution on any number of ranks: each scene on the
/// disk solved on PETSC_COMM_WORLD (METIS-distributed) against rank 0 alone (PETSC_COMM_SELF).
#include <catch2/catch.hpp>
#include <cmath>
#include <functional>

#include "hypershape/physics/material_params.hpp"
#include "hypershape/physics/registry.hpp"
#include "hypershape/solver/nonlinear.hpp"
#include "support/helpers.hpp"

using namespace hypershape;

// Named for the unity build (HS_UNITY_BUILD): files of one batch share a scope.
namespace mpi_test_effects {
namespace {

using Effects = std::function<std::vector<physics::EffectPtr>()>;

using hstest::broadcast;

/// The clamped disk with the given material and loads, solved at load factor `alpha`.
std::vector<double> solve(MPI_Comm comm, const Effects& effects, double alpha, bool& converged, int degree = 1) {
  mesh::MeshData m;
  if (core::rank(comm) == 0) m = hstest::disk_mesh(degree == 1 ? 0.1 : 0.2);
  physics::Problem p(comm, m, effects(), hstest::degree(degree));
  solver::NonlinearSolver ns(p);
  converged = ns.solve(alpha).converged;
  return p.gather(ns.solution()).values;
}

std::vector<physics::EffectPtr> scene(physics::EffectPtr material, physics::EffectPtr load) {
  std::vector<physics::EffectPtr> e;
  e.push_back(std::move(material));
  e.push_back(physics::make_dirichlet_patch({1.0, 0.0}, 0.5));
  e.push_back(std::move(load));
  return e;
}

physics::EffectPtr traction() { return physics::make_gaussian_traction({-1.0, 0.0}, {0.0, 1.0}, 0.2); }

}  // namespace

TEST_CASE("Catalogue effects have the same solution on any number of ranks", "[mpi][effects]") {
  const physics::ScalarFunction field = [f = physics::LogNormalField(2, 0.4, 0.3, 5)](const double* x) { return f(x); };
  struct Case {
    const char* name;
    Effects effects;
    int degree = 1;
  };
  const Case cases[] = {
      {"saint_venant_kirchhoff", [] { return scene(physics::make_saint_venant_kirchhoff(500, 0.4), traction()); }},
      {"mooney_rivlin", [] { return scene(physics::make_mooney_rivlin(60, 20, 800), traction()); }},
      {"linear_elastic", [] { return scene(physics::make_linear_elastic(500, 0.4), traction()); }},
      {"neo_hookean with a modulus field", [field] { return scene(physics::make_neo_hookean(500, 0.4, field), traction()); }},
      {"pressure on a ball region",
       [] { return scene(physics::make_neo_hookean(500, 0.4), physics::make_pressure(1.0, physics::Region::ball({-1, 0}, 0.8), 2)); }},
      {"follower pressure on a ball region (issue 18: LU solves)",
       [] {
         return scene(physics::make_neo_hookean(500, 0.4),
                      physics::make_follower_pressure(1.0, physics::Region::ball({-1, 0}, 0.8), 2));
       }},
      {"uniform traction on a box region",
       [] {
         return scene(physics::make_neo_hookean(500, 0.4),
                      physics::make_uniform_traction({0.0, -2.0}, physics::Region::box({-1, 0}, {0, 1})));
       }},
      {"spring foundation on a box region (issue 18)",
       [] {
         auto e = scene(physics::make_neo_hookean(500, 0.4), traction());
         e.push_back(physics::make_spring(50.0, 20.0, physics::Region::box({-1, -1}, {0, 1})));
         return e;
       }},
      {"two Dirichlet supports: the patch and a clamped region (issue 18)",
       [] {
         auto e = scene(physics::make_neo_hookean(500, 0.4), traction());
         e.push_back(physics::make_dirichlet("region", physics::Region::ball({0, -1}, 0.4).facets()));
         return e;
       }},
      {"neo_hookean with inclusions (issue 18)",
       [inc = physics::InclusionField(2, 4, 0.3, 5.0, 3)] {
         return scene(physics::make_neo_hookean(500, 0.4, [inc](const double* x) { return inc(x); }), traction());
       }},
      {"neo_hookean with dilatation: mean, nu 0.499, P2, with a modulus field",
       [field] { return scene(physics::make_neo_hookean_mean_dilatation(500, 0.499, field), traction()); }, 2},
  };
  for (const auto& [name, effects, degree] : cases) {
    DYNAMIC_SECTION(name) {
      bool ref_ok = false, ok = false;
      std::vector<double> ref;
      if (core::rank(PETSC_COMM_WORLD) == 0) ref = solve(PETSC_COMM_SELF, effects, 10.0, ref_ok, degree);
      const std::vector<double> u = solve(PETSC_COMM_WORLD, effects, 10.0, ok, degree);
      double d = 0, scale = 0;
      for (std::size_t i = 0; i < ref.size() && i < u.size(); ++i)
        d = std::max(d, std::abs(u[i] - ref[i])), scale = std::max(scale, std::abs(ref[i]));
      const double rel = broadcast(core::rank(PETSC_COMM_WORLD) == 0 && u.size() == ref.size() ? d / scale : 1.0);
      INFO("ranks " << core::size(PETSC_COMM_WORLD) << ": max|u| " << broadcast(scale) << ", relative difference " << rel);
      CHECK(broadcast(ref_ok) == 1.0);
      CHECK(ok);
      CHECK(broadcast(scale) > 1e-3);
      CHECK(rel < 1e-9);
    }
  }
}

TEST_CASE("A follower pressure's displacement-controlled path is the same on any number of ranks", "[mpi][effects][follower]") {
  // Not conservative (pressure on part of a free boundary): LU solves (PETSc's on one rank, MUMPS
  // on several), the residual line search, the symmetric part's inertia as the stability check.
  auto run = [](MPI_Comm comm, double& alpha, bool& converged, double& residual) {
    mesh::MeshData m;
    if (core::rank(comm) == 0) m = hstest::disk_mesh(0.1);
    physics::Problem p(comm, m,
                       scene(physics::make_neo_hookean(500, 0.4),
                             physics::make_follower_pressure(1.0, physics::Region::ball({-1, 0}, 0.8), 2)),
                       hstest::degree(1));
    solver::NonlinearSolver ns(p);
    const solver::TargetResult t = ns.solve_for_target(0.15);
    converged = t.converged && t.negative_pivots == 0;
    alpha = t.alpha;
    core::VecH r = p.create_vector();
    p.residual(ns.solution(), t.alpha, r);
    PetscReal rn;
    HS_PETSC(VecNorm(r, NORM_2, &rn));
    residual = rn / (t.alpha * p.load_norm());
    return p.gather(ns.solution()).values;
  };
  double alpha_ref = 0, alpha = 0, res_ref = 0, res = 0;
  bool ok_ref = false, ok = false;
  std::vector<double> ref;
  if (core::rank(PETSC_COMM_WORLD) == 0) ref = run(PETSC_COMM_SELF, alpha_ref, ok_ref, res_ref);
  const std::vector<double> u = run(PETSC_COMM_WORLD, alpha, ok, res);
  double d = 0, scale = 0;
  for (std::size_t i = 0; i < ref.size() && i < u.size(); ++i)
    d = std::max(d, std::abs(u[i] - ref[i])), scale = std::max(scale, std::abs(ref[i]));
  const double rel = broadcast(core::rank(PETSC_COMM_WORLD) == 0 && u.size() == ref.size() ? d / scale : 1.0);
  INFO("ranks " << core::size(PETSC_COMM_WORLD) << ": alpha " << alpha << " (one rank " << broadcast(alpha_ref)
                << "), true residual / (alpha |f|) " << res << ", relative difference in u " << rel);
  CHECK(broadcast(ok_ref) == 1.0);
  CHECK(ok);
  CHECK(res <= 1e-9);
  CHECK(rel < 1e-9);
  CHECK(std::abs(alpha / broadcast(alpha_ref) - 1) < 1e-9);
}

}  // namespace mpi_test_effects
