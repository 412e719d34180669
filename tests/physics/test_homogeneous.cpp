/// Homogeneous finite deformation of the unit square (plane strain) and cube under a uniform
/// dead traction T e_x on x = 1, with rollers on x = 0, y = 0 (and z = 0): the exact solution
/// F = diag(a, b[, b]) is linear in x, so P1 and P2 must reproduce it to solver tolerance.
#include <catch2/catch.hpp>
#include <cmath>

#include "hypershape/physics/neo_hookean.hpp"
#include "hypershape/solver/nonlinear.hpp"
#include "support/helpers.hpp"

using namespace hypershape;
using hstest::on_plane;

namespace {

/// Lateral stretch b with P22 = 0 at axial stretch a (plane strain: J = a b; 3D: J = a b^2), by
/// scalar Newton on P22(b) = mu (b - 1/b) + lambda ln J / b.
double lateral_stretch(int dim, double a, double mu, double lambda) {
  const int nl = dim - 1;  // number of lateral directions
  double b = 1.0;
  for (int it = 0; it < 60; ++it) {
    const double lnJ = std::log(a) + nl * std::log(b);
    const double g = mu * (b - 1.0 / b) + lambda * lnJ / b;
    const double dg = mu * (1.0 + 1.0 / (b * b)) + lambda * (nl - lnJ) / (b * b);
    const double step = g / dg;
    b -= step;
    if (std::abs(step) < 1e-15) break;
  }
  return b;
}

/// P11 at F = diag(a, b[, b]).
double axial_stress(int dim, double a, double b, double mu, double lambda) {
  const double lnJ = std::log(a) + (dim - 1) * std::log(b);
  return mu * (a - 1.0 / a) + lambda * lnJ / a;
}

}  // namespace

TEST_CASE("Uniaxial dead traction gives the closed-form homogeneous deformation", "[homogeneous]") {
  const double E = 500.0, a = 1.2;  // 20% axial stretch
  for (int dim : {2, 3})
    for (int deg : {1, 2})
      for (double nu : {0.3, 0.49}) {
        DYNAMIC_SECTION(dim << "D P" << deg << " nu " << nu) {
          const physics::Lame l = physics::Lame::from_young_poisson(E, nu);
          const double b = lateral_stretch(dim, a, l.mu, l.lambda);
          const double T = axial_stress(dim, a, b, l.mu, l.lambda);
          // The closed form itself: P22 = 0 at the computed b, and the lateral contraction has
          // the expected sign and rough size.
          {
            const double lnJ = std::log(a) + (dim - 1) * std::log(b);
            REQUIRE(std::abs(l.mu * (b - 1 / b) + l.lambda * lnJ / b) < 1e-10 * l.mu);
            REQUIRE(b < 1.0);
            REQUIRE(b > 0.75);
          }
          INFO("a = " << a << ", b = " << b << ", T = " << T);

          std::vector<physics::EffectPtr> effects;
          effects.push_back(physics::make_neo_hookean(E, nu));
          effects.push_back(physics::make_dirichlet("roller_x", on_plane(0, 0.0), {0}));
          effects.push_back(physics::make_dirichlet("roller_y", on_plane(1, 0.0), {1}));
          if (dim == 3)
            effects.push_back(physics::make_dirichlet("roller_z", on_plane(2, 0.0), {2}));
          effects.push_back(physics::make_surface_traction(
              [T, dim](const double*, double* t) {
                t[0] = T;
                for (int i = 1; i < dim; ++i) t[i] = 0.0;
              },
              on_plane(0, 1.0)));
          const mesh::MeshData m = mesh::mesh_box(dim, 1.0, dim == 2 ? 0.2 : 0.35);
          physics::Problem problem(PETSC_COMM_WORLD, m, std::move(effects), hstest::degree(deg));
          // Total nominal force = T * (area of the x = 1 face = 1).
          PetscScalar total = 0;
          {
            core::VecH ex = problem.create_vector();
            hstest::interpolate(
                problem,
                [](const double*, double* v) {
                  v[0] = 1.0;
                  v[1] = v[2] = 0.0;
                },
                ex);
            HS_PETSC(VecDot(problem.load(), ex, &total));
          }
          // (x-dofs on the roller x = 0 are constrained, so only the x = 1 face contributes.)
          CHECK(total == Approx(T).epsilon(1e-12));

          solver::SolverOptions so;
          so.rtol = 1e-11;
          solver::NonlinearSolver ns(problem, so);
          const solver::SolveResult res = ns.solve(1.0);
          INFO("solver: " << res.reason << ", " << res.newton_iterations << " Newton iterations, "
                          << res.increments << " increments");
          REQUIRE(res.converged);

          const physics::NodalField u = problem.gather(ns.solution());
          const auto& X = problem.space().canonical_coords();
          REQUIRE(u.values.size() == X.size());
          REQUIRE(std::int64_t(X.size()) == problem.space().n_nodes_global() * dim);
          double err = 0;
          for (std::size_t n = 0; n * dim < X.size(); ++n) {
            const double* x = &X[n * dim];
            const double* v = &u.values[n * dim];
            err = std::max(err, std::abs(v[0] - (a - 1.0) * x[0]));
            for (int i = 1; i < dim; ++i) err = std::max(err, std::abs(v[i] - (b - 1.0) * x[i]));
          }
          INFO("max nodal error " << err);
          CHECK(err < 1e-8);
          CHECK(res.max_displacement ==
                Approx(std::sqrt((a - 1) * (a - 1) + (dim - 1) * (b - 1) * (b - 1))).epsilon(1e-8));
          CHECK(problem.min_det_f(ns.solution()) == Approx(a * std::pow(b, dim - 1)).epsilon(1e-8));
        }
      }
}
