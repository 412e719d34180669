/// The modulus field W(x, F) = m(x) W(F): a two-layer (bimaterial) plate in uniaxial stretch
/// against its closed form, and the log-normal field's statistics and determinism.
#include <catch2/catch.hpp>
#include <cmath>

#include "hypershape/core/error.hpp"
#include "hypershape/physics/material_params.hpp"
#include "support/helpers.hpp"

using namespace hypershape;

namespace {

/// The unit square as n x n squares cut into two counter-clockwise triangles: y = 1/2 is a mesh
/// line for even n, so a field with a jump there is resolved exactly by the cell rule.
mesh::MeshData structured_square(int n) {
  mesh::MeshData m;
  m.dim = 2;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) m.coords.insert(m.coords.end(), {double(i) / n, double(j) / n});
  auto v = [n](int i, int j) { return j * (n + 1) + i; };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      m.cells.insert(m.cells.end(), {v(i, j), v(i + 1, j), v(i + 1, j + 1), v(i, j), v(i + 1, j + 1), v(i, j + 1)});
  return m;
}

}  // namespace

TEST_CASE("A two-layer plate in uniaxial stretch has the closed-form layered solution", "[field]") {
  // Layers y < 1/2 (E1) and y > 1/2 (E2) loaded in parallel along x with rollers on x = 0 and
  // y = 0: F = diag(a, b) everywhere (b does not depend on E at fixed nu), and the dead traction
  // that holds it is t = E(y) / E P11(a, b) e_x, the layer's own stress. The force is the mean.
  const double E = 500, nu = 0.3, m1 = 1.0, m2 = 4.0, a = 1.1;
  auto m = [=](const double* x) { return x[1] < 0.5 ? m1 : m2; };
  const physics::Lame l = physics::Lame::from_young_poisson(E, nu);
  // Neo-Hookean plane strain: P22 = mu (b - 1/b) + lambda ln(ab) / b = 0, by bisection.
  double lo = 0.5, hi = 1.0;
  auto p22 = [&](double b) { return l.mu * (b - 1 / b) + l.lambda * std::log(a * b) / b; };
  for (int it = 0; it < 200; ++it) (p22(0.5 * (lo + hi)) < 0 ? lo : hi) = 0.5 * (lo + hi);
  const double b = 0.5 * (lo + hi), T = l.mu * (a - 1 / a) + l.lambda * std::log(a * b) / a;
  for (int deg : {1, 2}) {
    DYNAMIC_SECTION("P" << deg) {
      std::vector<physics::EffectPtr> effects;
      effects.push_back(physics::make_neo_hookean(E, nu, m));
      effects.push_back(physics::make_dirichlet("roller_x", hstest::on_plane(0, 0.0), {0}));
      effects.push_back(physics::make_dirichlet("roller_y", hstest::on_plane(1, 0.0), {1}));
      effects.push_back(physics::make_surface_traction(
          [=](const double* x, double* t) { t[0] = m(x) * T, t[1] = 0; }, hstest::on_plane(0, 1.0)));
      physics::Problem problem(PETSC_COMM_WORLD, structured_square(8), std::move(effects), hstest::degree(deg));
      solver::SolverOptions so;
      so.rtol = 1e-11;
      solver::NonlinearSolver ns(problem, so);
      REQUIRE(ns.solve(1.0).converged);
      const physics::NodalField u = problem.gather(ns.solution());
      const auto& X = problem.space().canonical_coords();
      double err = 0;
      for (std::size_t n = 0; 2 * n < X.size(); ++n)
        err = std::max({err, std::abs(u.values[2 * n] - (a - 1) * X[2 * n]),
                        std::abs(u.values[2 * n + 1] - (b - 1) * X[2 * n + 1])});
      INFO("a = " << a << ", b = " << b << ", T = " << T << ", max nodal error " << err);
      CHECK(err < 1e-9);
      // The force the rollers on x = 0 carry: the layers' mean stress times the height.
      const physics::Resultants r = problem.resultants(ns.solution(), 1.0);
      CHECK(-r.reaction_force[0] == Approx(0.5 * (m1 + m2) * T).epsilon(1e-8));
      // The same plate with a uniform modulus would be stretched less by the same load.
      CHECK(0.5 * (m1 + m2) * T > T);
    }
  }
}

TEST_CASE("The log-normal modulus field has its mean, spread and correlation length", "[field]") {
  const double cv = 0.5, length = 0.2;
  const physics::LogNormalField f(2, cv, length, 42);
  // Sample far-apart points (independent for |dx| >> length): mean ~1, cv ~0.5.
  double sum = 0, sum2 = 0, near = 0, far = 0;
  const int n = 4000;
  for (int i = 0; i < n; ++i) {
    const double x[2] = {3.0 * length * (i % 60), 3.0 * length * (i / 60)};
    const double v = f(x);
    sum += v, sum2 += v * v;
    const double y[2] = {x[0] + 0.05 * length, x[1]}, z[2] = {x[0] + 2.0 * length, x[1]};
    near += std::abs(f(y) - v), far += std::abs(f(z) - v);
  }
  const double mean = sum / n, sd = std::sqrt(sum2 / n - mean * mean);
  INFO("mean " << mean << ", cv " << sd / mean << ", mean |dm| at 0.05 l " << near / n << ", at 2 l " << far / n);
  CHECK(mean == Approx(1.0).margin(0.05));
  CHECK(sd / mean == Approx(cv).margin(0.08));
  CHECK(near < 0.2 * far);  // correlated at short range, not at long range
  // A pure function of (seed, x): the same seed gives the same field, another seed another.
  const double x[2] = {0.3, -0.7};
  CHECK(physics::LogNormalField(2, cv, length, 42)(x) == f(x));
  CHECK(physics::LogNormalField(2, cv, length, 43)(x) != f(x));
}

TEST_CASE("A material's modulus field comes from its keys", "[field]") {
  const core::MapParams p({{"E", 500.0}, {"nu", 0.3}, {"E_cv", 0.3}, {"E_length", 0.25}, {"E_seed", 7.0}});
  const physics::ScalarFunction field = physics::modulus_field(p, 2);
  REQUIRE(field);
  const double x[2] = {0.1, 0.2};
  CHECK(field(x) == physics::LogNormalField(2, 0.3, 0.25, 7)(x));
  CHECK_FALSE(physics::modulus_field(core::MapParams({{"E", 500.0}, {"nu", 0.3}}), 2));
  auto e = physics::make_effect("saint_venant_kirchhoff", p, 2);
  CHECK(e->channel() == "modulus");
  CHECK(e->channel_components(2) == 1);
  CHECK_THROWS_AS(physics::modulus_field(core::MapParams({{"E_cv", 0.3}, {"E_length", 0.25}, {"E_seed", 1.5}}), 2),
                  core::InputError);
}
