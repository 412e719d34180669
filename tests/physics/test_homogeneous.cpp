/// Homogeneous finite deformation of the unit square (plane strain) and cube under a uniform
/// dead traction T e_x on x = 1, with rollers on x = 0, y = 0 (and z = 0): the exact solution
/// F = diag(a, b[, b]) is linear in x, so P1 and P2 must reproduce it to solver tolerance. Each
/// material's closed form is written in principal stretches (l1, l2, l3), independently of its
/// kernel: P_i = dW/dl_i; b solves P_2(a, b, b or 1) = 0 and T = P_1.
#include <catch2/catch.hpp>
#include <cmath>
#include <functional>

#include "hypershape/physics/neo_hookean.hpp"
#include "hypershape/solver/nonlinear.hpp"
#include "support/helpers.hpp"

using namespace hypershape;
using hstest::on_plane;

// Named for the unity build (HS_UNITY_BUILD): files of one batch share a scope.
namespace test_homogeneous {
namespace {

/// Principal first Piola stress P_i at principal stretches l (3 of them), material constants
/// from (E, nu).
using PrincipalStress = std::function<double(int i, const double* l, double E, double nu)>;

double neo_hookean_p(int i, const double* l, double E, double nu) {
  const physics::Lame m = physics::Lame::from_young_poisson(E, nu);
  return m.mu * (l[i] - 1.0 / l[i]) + m.lambda * std::log(l[0] * l[1] * l[2]) / l[i];
}

double svk_p(int i, const double* l, double E, double nu) {
  const physics::Lame m = physics::Lame::from_young_poisson(E, nu);
  double e[3], tr = 0;
  for (int k = 0; k < 3; ++k) tr += (e[k] = 0.5 * (l[k] * l[k] - 1.0));
  return l[i] * (m.lambda * tr + 2.0 * m.mu * e[i]);
}

/// Mooney-Rivlin with mu = 2 (C1 + C2) split 70/30 and kappa the bulk modulus of (E, nu).
double mooney_rivlin_p(int i, const double* l, double E, double nu) {
  const physics::Lame m = physics::Lame::from_young_poisson(E, nu);
  const double C1 = 0.35 * m.mu, C2 = 0.15 * m.mu, kappa = m.lambda + 2.0 * m.mu / 3.0;
  const double J = l[0] * l[1] * l[2], I1 = l[0] * l[0] + l[1] * l[1] + l[2] * l[2],
               I2 = l[0] * l[0] * l[1] * l[1] + l[1] * l[1] * l[2] * l[2] +
                    l[0] * l[0] * l[2] * l[2];
  return C1 * std::pow(J, -2.0 / 3.0) * (2 * l[i] - 2.0 / 3.0 * I1 / l[i]) +
         C2 * std::pow(J, -4.0 / 3.0) * (2 * l[i] * (I1 - l[i] * l[i]) - 4.0 / 3.0 * I2 / l[i]) +
         kappa * (J - 1) * J / l[i];
}

double linear_elastic_p(int i, const double* l, double E, double nu) {
  const physics::Lame m = physics::Lame::from_young_poisson(E, nu);
  return m.lambda * (l[0] + l[1] + l[2] - 3.0) + 2.0 * m.mu * (l[i] - 1.0);
}

struct Material {
  const char* name;
  std::function<physics::EffectPtr(double E, double nu)> make;
  PrincipalStress p;
};

const Material materials[] = {
    {"neo_hookean", [](double e, double nu) { return physics::make_neo_hookean(e, nu); },
     neo_hookean_p},
    {"saint_venant_kirchhoff",
     [](double e, double nu) { return physics::make_saint_venant_kirchhoff(e, nu); }, svk_p},
    {"mooney_rivlin",
     [](double e, double nu) {
       const physics::Lame m = physics::Lame::from_young_poisson(e, nu);
       return physics::make_mooney_rivlin(0.35 * m.mu, 0.15 * m.mu, m.lambda + 2.0 * m.mu / 3.0);
     },
     mooney_rivlin_p},
    {"linear_elastic", [](double e, double nu) { return physics::make_linear_elastic(e, nu); },
     linear_elastic_p},
};

/// The lateral stretch b with P_2 = 0 at axial stretch a, by bisection on [0.5, 1.5].
double lateral_stretch(const PrincipalStress& p, int dim, double a, double E, double nu) {
  auto p2 = [&](double b) {
    const double l[3] = {a, b, dim == 3 ? b : 1.0};
    return p(1, l, E, nu);
  };
  double lo = 0.5, hi = 1.5;
  REQUIRE(p2(lo) * p2(hi) < 0);
  for (int it = 0; it < 200 && hi - lo > 1e-16; ++it) {
    const double mid = 0.5 * (lo + hi);
    (p2(mid) * p2(lo) > 0 ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace

TEST_CASE("Uniaxial dead traction gives the closed-form homogeneous deformation", "[homogeneous]") {
  const double E = 500.0, a = 1.2;  // 20% axial stretch
  for (const Material& mat : materials)
    for (int dim : {2, 3})
      for (int deg : {1, 2})
        for (double nu : {0.3, 0.49}) {
          if (nu == 0.49 && std::string(mat.name) != "neo_hookean") continue;
          DYNAMIC_SECTION(mat.name << " " << dim << "D P" << deg << " nu " << nu) {
            const double b = lateral_stretch(mat.p, dim, a, E, nu);
            const double l[3] = {a, b, dim == 3 ? b : 1.0};
            const double T = mat.p(0, l, E, nu);
            REQUIRE(std::abs(mat.p(1, l, E, nu)) < 1e-10 * E);
            REQUIRE(b < 1.0);
            REQUIRE(b > 0.75);
            INFO("a = " << a << ", b = " << b << ", T = " << T);

            std::vector<physics::EffectPtr> effects;
            effects.push_back(mat.make(E, nu));
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
            CHECK(
                res.max_displacement ==
                Approx(std::sqrt((a - 1) * (a - 1) + (dim - 1) * (b - 1) * (b - 1))).epsilon(1e-8));
            CHECK(problem.min_det_f(ns.solution()) ==
                  Approx(a * std::pow(b, dim - 1)).epsilon(1e-8));
          }
        }
}

}  // namespace test_homogeneous
