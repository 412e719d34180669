/// Inclusions as a modulus field: the field's values at known points (centres, just inside and
/// just outside each ball, far away), its determinism in the seed, the keys through a material
/// (the `modulus` channel), and a disc inclusion stiffer than the matrix carrying a uniaxial
/// load: the homogeneous matrix (ratio 1) reproduces the closed form, a stiff inclusion makes
/// the plate stiffer and a soft one softer, as springs in series and parallel bound it.
#include <catch2/catch.hpp>
#include <cmath>

#include "hypershape/core/error.hpp"
#include "hypershape/physics/material_params.hpp"
#include "hypershape/solver/nonlinear.hpp"
#include "support/helpers.hpp"

using namespace hypershape;
using core::MapParams;
using Vector = std::vector<double>;

TEST_CASE("Inclusions: ratio inside each ball, 1 outside, a pure function of the seed", "[field]") {
  for (int dim : {2, 3})
    DYNAMIC_SECTION(dim << "D") {
      const double r = 0.15, ratio = 7.0;
      const physics::InclusionField f(dim, 5, r, ratio, 42);
      const auto& c = f.centers();
      REQUIRE(c.size() == std::size_t(5 * dim));
      for (double v : c) CHECK(std::abs(v) <= 1.0);
      auto nearest = [&](const double* x) {  // distance to the nearest centre, brute force
        double best = 1e300;
        for (std::size_t k = 0; k < c.size(); k += std::size_t(dim)) {
          double d2 = 0;
          for (int i = 0; i < dim; ++i) d2 += (x[i] - c[k + std::size_t(i)]) * (x[i] - c[k + std::size_t(i)]);
          best = std::min(best, std::sqrt(d2));
        }
        return best;
      };
      for (std::size_t k = 0; k < c.size(); k += std::size_t(dim)) {
        double x[3] = {0, 0, 0};
        for (int i = 0; i < dim; ++i) x[i] = c[k + std::size_t(i)];
        CHECK(f(x) == ratio);  // the centre
        x[0] += 0.99 * r;
        CHECK(f(x) == ratio);  // just inside
        x[0] += 0.02 * r;
        CHECK(f(x) == (nearest(x) <= r ? ratio : 1.0));  // just outside (unless another ball)
      }
      const double far[3] = {5, 5, 5};
      CHECK(f(far) == 1.0);
      const physics::InclusionField same(dim, 5, r, ratio, 42), other(dim, 5, r, ratio, 43);
      CHECK(same.centers() == c);
      CHECK(other.centers() != c);
    }
}

TEST_CASE("Inclusions through a material's keys: the modulus channel; bad keys named", "[field]") {
  const MapParams p({{"E", 500.0}, {"nu", 0.3}, {"inclusions", 3.0}, {"inclusion_radius", 0.2},
                     {"inclusion_ratio", 4.0}, {"E_seed", 9.0}});
  const physics::EffectPtr m = physics::make_effect("neo_hookean", p, 2);
  REQUIRE(m->channel() == "modulus");
  const physics::InclusionField f(2, 3, 0.2, 4.0, 9);
  double v = 0;
  m->channel_value(f.centers().data(), &v);
  CHECK(v == 4.0);
  const double far[2] = {5, 5};
  m->channel_value(far, &v);
  CHECK(v == 1.0);
  // With a log-normal field as well: the product.
  MapParams q = p;
  q.set("E_cv", 0.3).set("E_length", 0.2);
  const physics::EffectPtr both = physics::make_effect("mooney_rivlin",
                                                       MapParams(q).set("C1", 50.0).set("C2", 10.0).set("kappa", 800.0), 2);
  REQUIRE(both->channel() == "modulus");
  double w = 0;
  both->channel_value(f.centers().data(), &w);
  const physics::LogNormalField ln(2, 0.3, 0.2, 9);
  CHECK(w == Approx(4.0 * ln(f.centers().data())).epsilon(1e-14));

  auto message = [](MapParams params) {
    try {
      physics::make_effect("neo_hookean", params.set("E", 500.0).set("nu", 0.3), 2);
    } catch (const core::InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  CHECK_THAT(message(MapParams({{"inclusions", 2.0}, {"inclusion_radius", 0.2}})), Catch::Contains("inclusion_ratio"));
  CHECK_THAT(message(MapParams({{"inclusions", 1.5}, {"inclusion_radius", 0.2}, {"inclusion_ratio", 2.0}})),
             Catch::Contains("inclusions"));
  CHECK_THAT(message(MapParams({{"inclusions", 1.0}, {"inclusion_radius", -0.2}, {"inclusion_ratio", 2.0}})),
             Catch::Contains("inclusion_radius"));
  CHECK_THAT(message(MapParams({{"inclusions", 1.0}, {"inclusion_radius", 0.2}, {"inclusion_ratio", 0.0}})),
             Catch::Contains("inclusion_ratio"));
  CHECK_THAT(message(MapParams({{"inclusion_ratio", 2.0}})), Catch::Contains("inclusion_ratio"));
  CHECK_THAT(message(MapParams({{"E_seed", 2.0}})), Catch::Contains("E_seed"));
}

namespace {

/// The unit square in linear elasticity (E = 100, nu = 0.3, modulus factor `field`), rollers on
/// x = 0 and y = 0, traction T e_x on x = 1: the mean u_x on x = 1 over T (a compliance).
double compliance(const physics::ScalarFunction& field, int degree) {
  const double T = 1.0;
  std::vector<physics::EffectPtr> e;
  e.push_back(physics::make_linear_elastic(100.0, 0.3, field));
  e.push_back(physics::make_dirichlet("rx", hstest::on_plane(0, 0.0), {0}));
  e.push_back(physics::make_dirichlet("ry", hstest::on_plane(1, 0.0), {1}));
  e.push_back(physics::make_uniform_traction({T, 0.0}, physics::Region::box({1, 0}, {1, 1})));
  physics::Problem pb(PETSC_COMM_WORLD, mesh::mesh_box(2, 1.0, 0.04), std::move(e), hstest::degree(degree));
  solver::SolverOptions so;
  so.rtol = 1e-12;
  solver::NonlinearSolver ns(pb, so);
  REQUIRE(ns.solve(1.0).converged);
  // Work of the load = T * int u_x dS on x = 1 = load . u.
  PetscScalar work;
  HS_PETSC(VecDot(pb.load(), ns.solution(), &work));
  return PetscRealPart(work) / (T * T);
}

}  // namespace

TEST_CASE("A disc inclusion stiffens or softens a plate within the series and parallel bounds", "[field]") {
  // Inclusion of area fraction f = pi r^2 = 0.1257 (r = 0.2, centre (0.5, 0.5)): the plate's
  // compliance lies between the Reuss (series) and Voigt (parallel) mixtures of the two moduli.
  const double nu = 0.3, E = 100.0, r = 0.2, frac = M_PI * r * r;
  const double c1 = compliance({}, 2);
  const double exact = (1 - nu * nu) / E;  // plane strain uniaxial stress
  INFO("homogeneous compliance " << c1 << ", closed form " << exact);
  CHECK(c1 == Approx(exact).epsilon(1e-9));
  for (double ratio : {5.0, 0.2}) {
    auto disc = [=](const double* x) {
      return (x[0] - 0.5) * (x[0] - 0.5) + (x[1] - 0.5) * (x[1] - 0.5) <= r * r ? ratio : 1.0;
    };
    const double c = compliance(disc, 2);
    const double reuss = exact * (1 - frac + frac / ratio), voigt = exact / (1 - frac + frac * ratio);
    INFO("ratio " << ratio << ": compliance " << c << ", Voigt " << voigt << ", Reuss " << reuss);
    CHECK(c > voigt);
    CHECK(c < reuss);
    CHECK((ratio > 1 ? c < exact : c > exact));
  }
}
