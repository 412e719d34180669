/// The materials of the catalogue (Saint Venant-Kirchhoff, compressible Mooney-Rivlin, linear
/// elasticity): stress = dW/dF and tangent = dP/dF by finite differences, plane strain = 3D
/// with F_33 = 1, the reference state stress free with the linear-elastic tangent (the
/// small-load limit), objectivity; on meshes: the residual is the gradient of the energy, the
/// tangent the derivative of the residual, the hand-written loops equal PETSc's pointwise
/// assembly, a small load gives the linear-elastic solution, uniaxial stretch of a box gives the
/// closed-form homogeneous deformation, and bad parameters are rejected with the key named.
#include <catch2/catch.hpp>
#include <cmath>
#include <random>

#include "hypershape/core/error.hpp"
#include "hypershape/physics/linear_elastic.hpp"
#include "hypershape/physics/mooney_rivlin.hpp"
#include "hypershape/physics/registry.hpp"
#include "hypershape/physics/saint_venant_kirchhoff.hpp"
#include "support/helpers.hpp"
#include "support/kernel_checks.hpp"

using namespace hypershape;
using namespace hypershape::physics;

// Named for the unity build (HS_UNITY_BUILD): files of one batch share a scope.
namespace test_materials {
namespace {

constexpr double E = 500.0, NU = 0.3;

/// Mooney-Rivlin with the linearised E, nu: mu = 2 (C1 + C2) split 70/30, kappa = E / (3(1-2nu)).
MooneyRivlinModel mooney_rivlin_like(double E_, double nu) {
  const Lame l = Lame::from_young_poisson(E_, nu);
  return {0.35 * l.mu, 0.15 * l.mu, l.lambda + 2.0 * l.mu / 3.0};
}

template <int D>
SaintVenantKirchhoff<D> svk(double nu = NU) {
  const Lame l = Lame::from_young_poisson(E, nu);
  return {{{l.mu, l.lambda}}};
}
template <int D>
MooneyRivlin<D> mr(double nu = NU) {
  return {{mooney_rivlin_like(E, nu)}};
}
template <int D>
LinearElastic<D> le(double nu = NU) {
  const Lame l = Lame::from_young_poisson(E, nu);
  return {l.mu, l.lambda};
}

template <int D>
Tensor<D> random_f(std::mt19937_64& rng) {
  return hstest::random_f<D>(rng, 0.35, 0.3);
}
using hstest::fd4;

template <int D, class K>
void check_derivatives(const K& m, const char* name) {
  std::mt19937_64 rng(77 + D);
  for (int sample = 0; sample < 8; ++sample) {
    const Tensor<D> F = random_f<D>(rng);
    INFO(name << " D = " << D << " sample " << sample << " F =\n" << F);
    Tensor<D> P, P2, P_fd;
    Tangent<D> A, A_fd;
    double W;
    REQUIRE(m.energy(F, W));
    REQUIRE(m.stress(F, P));
    REQUIRE(m.stress_tangent(F, P2, A));
    CHECK((P2 - P).norm() <= 1e-14 * P.norm());
    const double h = 1e-4;
    for (int k = 0; k < D; ++k)
      for (int l = 0; l < D; ++l) {
        P_fd(k, l) = fd4<D>([&](const Tensor<D>& G) { double w = 0; m.energy(G, w); return w; }, F, k, l, h);
        const Tensor<D> dP =
            fd4<D>([&](const Tensor<D>& G) { Tensor<D> p; m.stress(G, p); return Tensor<D>(p); }, F, k, l, h);
        for (int i = 0; i < D; ++i)
          for (int J = 0; J < D; ++J) A_fd(i * D + J, k * D + l) = dP(i, J);
      }
    CHECK((P - P_fd).norm() <= 1e-7 * P.norm());
    CHECK((A - A_fd).norm() <= 1e-7 * A.norm());
    CHECK((A - A.transpose()).norm() <= 1e-12 * A.norm());
  }
}

/// At F = I: W = 0, P = 0 and A = the isotropic linear-elastic C of (E, nu).
template <int D, class K>
void check_reference_state(const K& m, double nu) {
  const Tensor<D> I = Tensor<D>::Identity();
  double W = 1.0;
  Tensor<D> P;
  Tangent<D> A, C;
  REQUIRE(m.energy(I, W));
  REQUIRE(m.stress_tangent(I, P, A));
  CHECK(std::abs(W) <= 1e-13 * E);
  CHECK(P.norm() <= 1e-12 * E);
  const Lame l = Lame::from_young_poisson(E, nu);
  for (int i = 0; i < D; ++i)
    for (int J = 0; J < D; ++J)
      for (int k = 0; k < D; ++k)
        for (int L = 0; L < D; ++L)
          C(i * D + J, k * D + L) = l.lambda * (i == J) * (k == L) + l.mu * ((i == k) * (J == L) + (i == L) * (J == k));
  CHECK((A - C).norm() <= 1e-12 * C.norm());
}

/// W(QF) = W(F), P(QF) = Q P(F) for rotations Q (nonlinear materials only).
template <int D, class K>
void check_objectivity(const K& m) {
  std::mt19937_64 rng(5 + D);
  for (int sample = 0; sample < 6; ++sample) {
    const Tensor<D> Q = hstest::random_rotation<D>(rng);
    const Tensor<D> F = random_f<D>(rng);
    double W = 0, WQ = 0;
    Tensor<D> P, PQ;
    REQUIRE((m.energy(F, W) && m.energy(Q * F, WQ) && m.stress(F, P) && m.stress(Q * F, PQ)));
    CHECK(std::abs(WQ - W) <= 1e-12 * std::abs(W));
    CHECK((PQ - Q * P).norm() <= 1e-12 * P.norm());
  }
}

/// The 2D kernel is the 3D one with F_33 = 1 (plane strain).
template <class K2, class K3>
void check_plane_strain(const K2& m2, const K3& m3) {
  std::mt19937_64 rng(11);
  const Tensor<2> F = random_f<2>(rng);
  Tensor<3> F3 = Tensor<3>::Identity();
  F3.topLeftCorner<2, 2>() = F;
  double W2 = 0, W3 = 0;
  Tensor<2> P2;
  Tensor<3> P3;
  REQUIRE((m2.energy(F, W2) && m3.energy(F3, W3) && m2.stress(F, P2) && m3.stress(F3, P3)));
  CHECK(W2 == Approx(W3).epsilon(1e-13));
  CHECK((P2 - P3.topLeftCorner<2, 2>()).norm() <= 1e-12 * P2.norm());
}

}  // namespace

TEST_CASE("Catalogue materials: stress and tangent match finite differences", "[kernel][materials]") {
  for (double nu : {0.3, 0.45}) {
    check_derivatives<2>(svk<2>(nu), "svk");
    check_derivatives<3>(svk<3>(nu), "svk");
    check_derivatives<2>(mr<2>(nu), "mooney_rivlin");
    check_derivatives<3>(mr<3>(nu), "mooney_rivlin");
    check_derivatives<2>(le<2>(nu), "linear_elastic");
    check_derivatives<3>(le<3>(nu), "linear_elastic");
  }
}

TEST_CASE("Catalogue materials linearise to the linear-elastic tangent of the same E and nu",
          "[kernel][materials]") {
  for (double nu : {0.3, 0.49}) {
    check_reference_state<2>(svk<2>(nu), nu);
    check_reference_state<3>(svk<3>(nu), nu);
    check_reference_state<2>(mr<2>(nu), nu);
    check_reference_state<3>(mr<3>(nu), nu);
    check_reference_state<2>(le<2>(nu), nu);
    check_reference_state<3>(le<3>(nu), nu);
  }
}

TEST_CASE("Catalogue materials: objectivity, plane strain, the det F guard", "[kernel][materials]") {
  check_objectivity<2>(svk<2>());
  check_objectivity<3>(svk<3>());
  check_objectivity<2>(mr<2>());
  check_objectivity<3>(mr<3>());
  check_plane_strain(svk<2>(), svk<3>());
  check_plane_strain(mr<2>(), mr<3>());
  check_plane_strain(le<2>(), le<3>());
  Tensor<3> reflect = Tensor<3>::Identity();
  reflect(0, 0) = -1;
  double W = 42;
  CHECK_FALSE(svk<3>().energy(reflect, W));
  CHECK_FALSE(mr<3>().energy(reflect, W));
  CHECK(W == 42);
  CHECK(le<3>().energy(reflect, W));  // the linear problem has no guard
  Tensor<3> nan_f = Tensor<3>::Identity();
  nan_f(0, 1) = std::nan("");
  CHECK_FALSE(le<3>().energy(nan_f, W));
}

TEST_CASE("Mooney-Rivlin energy has the closed form on a diagonal stretch", "[kernel][materials]") {
  const MooneyRivlinModel m = mooney_rivlin_like(E, NU);
  const double a = 1.3, b = 0.8, c = 1.1, J = a * b * c;
  const double I1 = a * a + b * b + c * c, I2 = a * a * b * b + b * b * c * c + a * a * c * c;
  const double expected = m.C1 * (I1 / std::cbrt(J * J) - 3) + m.C2 * (I2 / std::cbrt(J * J * J * J) - 3) +
                          0.5 * m.kappa * (J - 1) * (J - 1);
  Tensor<3> F = Tensor<3>::Zero();
  F.diagonal() << a, b, c;
  double W;
  REQUIRE(MooneyRivlin<3>{{m}}.energy(F, W));
  CHECK(W == Approx(expected).epsilon(1e-13));
}

// ---- on meshes --------------------------------------------------------------------------------

namespace {

using Maker = std::function<EffectPtr(double E, double nu)>;
struct Material {
  const char* name;
  Maker make;
};

const Material materials[] = {
    {"saint_venant_kirchhoff", [](double e, double nu) { return make_saint_venant_kirchhoff(e, nu); }},
    {"mooney_rivlin",
     [](double e, double nu) {
       const MooneyRivlinModel m = mooney_rivlin_like(e, nu);
       return make_mooney_rivlin(m.C1, m.C2, m.kappa);
     }},
    {"linear_elastic", [](double e, double nu) { return make_linear_elastic(e, nu); }},
};

std::unique_ptr<Problem> disk_problem(EffectPtr material, int degree, double h = 0.2) {
  std::vector<EffectPtr> effects;
  effects.push_back(std::move(material));
  effects.push_back(make_dirichlet_patch({1.0, 0.0}, 0.5));
  effects.push_back(make_gaussian_traction({-1.0, 0.0}, {0.0, 1.0}, 0.2));
  return std::make_unique<Problem>(PETSC_COMM_WORLD, hstest::disk_mesh(h), std::move(effects), hstest::degree(degree));
}

/// Smooth, zero on the patch |x - (1, 0)| <= 0.5, gradients ~0.1-0.3.
void smooth_field(const double* x, double* u, double scale) {
  const double phi = std::max(0.0, (x[0] - 1.0) * (x[0] - 1.0) + x[1] * x[1] - 0.25) / 3.0;
  u[0] = scale * phi * (0.4 * std::sin(1.3 * x[0] + 0.4 * x[1]) + 0.15 * x[1] * x[1]);
  u[1] = scale * phi * (0.3 * std::cos(0.9 * x[0] - 1.1 * x[1]) - 0.2 * x[0] * x[1]);
}

/// Directional derivatives at u along v: energy vs residual, residual vs tangent (4th order).
void check_consistency(const Problem& p, Vec u, Vec v) {
  core::VecH w = p.create_vector(), r = p.create_vector(), rp = p.create_vector(), Jv = p.create_vector();
  const double eps = 1e-4;
  auto shifted = [&](double t) {
    HS_PETSC(VecWAXPY(w, t, v, u));
    return Vec(w);
  };
  auto energy = [&](double t) { double e = 0; REQUIRE(p.energy(shifted(t), 0.0, e)); return e; };
  const double dE = (-energy(2 * eps) + 8 * energy(eps) - 8 * energy(-eps) + energy(-2 * eps)) / (12 * eps);
  REQUIRE(p.residual(u, 0.0, r));
  PetscScalar rv;
  HS_PETSC(VecDot(r, v, &rv));
  INFO("dPi/dv = " << dE << ", r . v = " << rv);
  CHECK(dE == Approx(rv).epsilon(1e-7));
  // (r(u + eps v) - r(u - eps v)) / (2 eps) against J v.
  HS_PETSC(VecZeroEntries(rp));
  for (auto [t, c] : {std::pair{2 * eps, -1.0}, {eps, 8.0}, {-eps, -8.0}, {-2 * eps, 1.0}}) {
    REQUIRE(p.residual(shifted(t), 0.0, r));
    HS_PETSC(VecAXPY(rp, c / (12 * eps), r));
  }
  core::MatH J = p.create_matrix();
  REQUIRE(p.jacobian(u, J));
  HS_PETSC(MatMult(J, v, Jv));
  const double d = hstest::rel_diff(rp, Jv);
  INFO("|| dr/dv - J v || / || J v || = " << d);
  CHECK(d < 1e-8);
}

}  // namespace

TEST_CASE("Catalogue materials on a mesh: energy, residual and tangent are consistent",
          "[assembly][materials]") {
  for (const Material& m : materials)
    for (int degree : {1, 2}) {
      DYNAMIC_SECTION(m.name << " P" << degree) {
        auto p = disk_problem(m.make(E, 0.45), degree);
        core::VecH u = p->create_vector(), v = p->create_vector(), r = p->create_vector(),
                   r_pw = p->create_vector();
        hstest::interpolate(*p, [](const double* x, double* f) { smooth_field(x, f, 1.0); }, u);
        hstest::interpolate(*p, [](const double* x, double* f) {
          f[0] = 0.1 * x[1] * x[1] + 0.05;
          f[1] = -0.2 * x[0] * x[1];
        }, v);
        REQUIRE(p->min_det_f(u) < 0.97);
        check_consistency(*p, u, v);
        // The hand-written loops equal PETSc's pointwise assembly of the same kernel.
        REQUIRE(p->residual(u, 0.0, r));
        p->residual_pointwise(u, r_pw);
        CHECK(hstest::rel_diff(r_pw, r) < 1e-12);
        core::MatH J = p->create_matrix(), J_pw = p->create_matrix();
        REQUIRE(p->jacobian(u, J));
        p->jacobian_pointwise(u, J_pw);
        PetscReal jn, dn;
        HS_PETSC(MatNorm(J, NORM_FROBENIUS, &jn));
        HS_PETSC(MatAXPY(J_pw, -1.0, J, DIFFERENT_NONZERO_PATTERN));
        HS_PETSC(MatNorm(J_pw, NORM_FROBENIUS, &dn));
        CHECK(dn / jn < 1e-12);
      }
    }
}

TEST_CASE("Catalogue materials: a small load gives the linear-elastic solution", "[materials]") {
  // The nonlinear part of the response is second order in the load: halving the load halves
  // the relative difference to linear elasticity.
  auto solve = [](EffectPtr material, double alpha) {
    auto p = disk_problem(std::move(material), 1, 0.15);
    solver::SolverOptions so;
    so.rtol = 1e-12;
    solver::NonlinearSolver ns(*p, so);
    REQUIRE(ns.solve(alpha).converged);
    core::VecH u = p->create_vector();
    HS_PETSC(VecCopy(ns.solution(), u));
    return u;
  };
  for (const Material& m : materials) {
    if (std::string(m.name) == "linear_elastic") continue;
    DYNAMIC_SECTION(m.name) {
      double prev = 0;
      for (double alpha : {0.4, 0.2}) {
        core::VecH u = solve(m.make(E, 0.3), alpha), u_lin = solve(make_linear_elastic(E, 0.3), alpha);
        const double d = hstest::rel_diff(u, u_lin);
        INFO("alpha " << alpha << ": ||u - u_lin|| / ||u_lin|| = " << d);
        CHECK(d < 5e-3);
        if (prev > 0) CHECK(d / prev == Approx(0.5).margin(0.05));
        prev = d;
      }
    }
  }
}

TEST_CASE("Linear elasticity: one Newton step per increment and the exact alpha", "[materials]") {
  auto p = disk_problem(make_linear_elastic(E, 0.3), 1, 0.15);
  solver::SolverOptions so;
  so.rtol = 1e-10;
  solver::NonlinearSolver ns(*p, so);
  const solver::SolveResult one = ns.solve(1.0);
  REQUIRE(one.converged);
  INFO(one.newton_iterations << " Newton iterations in " << one.increments << " increments");
  CHECK(one.newton_iterations == one.increments);
  const double target = 0.1;
  const solver::TargetResult t = ns.solve_for_target(target);
  REQUIRE(t.converged);
  INFO("alpha " << t.alpha << ", max|u| " << t.max_displacement << " (at alpha 1: " << one.max_displacement << ")");
  CHECK(t.alpha == Approx(target / one.max_displacement).epsilon(1e-9));
  CHECK(t.max_displacement == Approx(target).epsilon(1e-9));
}

TEST_CASE("Catalogue materials reject bad parameters naming the key", "[materials][input]") {
  struct Bad {
    const char* effect;
    core::MapParams params;
    const char* key;
  };
  const Bad cases[] = {
      {"saint_venant_kirchhoff", core::MapParams({{"E", -1.0}, {"nu", 0.3}}), "E"},
      {"saint_venant_kirchhoff", core::MapParams({{"E", 1.0}, {"nu", 0.5}}), "nu"},
      {"linear_elastic", core::MapParams({{"E", 1.0}}), "nu"},
      {"mooney_rivlin", core::MapParams({{"C1", -1.0}, {"C2", 1.0}, {"kappa", 1.0}}), "C1"},
      {"mooney_rivlin", core::MapParams({{"C1", 0.0}, {"C2", 0.0}, {"kappa", 1.0}}), "C1 + C2"},
      {"mooney_rivlin", core::MapParams({{"C1", 1.0}, {"C2", 1.0}}), "kappa"},
      {"mooney_rivlin", core::MapParams({{"C1", 1.0}, {"C2", 1.0}, {"kappa", 1.0}, {"D1", 1.0}}), "kappa"},
      {"mooney_rivlin", core::MapParams({{"C1", 1.0}, {"C2", 1.0}, {"D1", 0.0}}), "D1"},
      {"neo_hookean", core::MapParams({{"E", 1.0}, {"nu", 0.3}, {"E_cv", 0.5}}), "E_length"},
      {"neo_hookean", core::MapParams({{"E", 1.0}, {"nu", 0.3}, {"E_cv", -0.5}, {"E_length", 0.1}}), "E_cv"},
      {"linear_elastic", core::MapParams({{"E", 1.0}, {"nu", 0.3}, {"E_length", 0.1}}), "E_length"},
      {"neo_hookean", core::MapParams({{"E", 1.0}, {"nu", 0.3}, {"dilatation", std::string("average")}}), "dilatation"},
      {"neo_hookean", core::MapParams({{"E", 1.0}, {"nu", 0.3}, {"pointwise_share", 0.1}}), "pointwise_share"},
      {"neo_hookean",
       core::MapParams({{"E", 1.0}, {"nu", 0.3}, {"dilatation", std::string("mean")}, {"pointwise_share", 1.0}}),
       "pointwise_share"},
  };
  for (const Bad& b : cases) {
    INFO(b.effect << ": expecting a message naming " << b.key);
    try {
      make_effect(b.effect, b.params, 2);
      FAIL("accepted");
    } catch (const core::InputError& e) {
      CHECK_THAT(e.what(), Catch::Contains(b.key));
    }
  }
}

// ---- the mean-dilatation Neo-Hookean (dilatation: mean) ----------------------------------------

TEST_CASE("Mean dilatation: energy, residual and tangent consistent; the pointwise material where J is constant per cell",
          "[assembly][materials][mean_dilatation]") {
  auto residual = [](const Problem& p, Vec u) {
    core::VecH r = p.create_vector();
    REQUIRE(p.residual(u, 0.0, r));
    return r;
  };
  for (const double nu : {0.45, 0.499})
    for (int degree : {1, 2}) {
      DYNAMIC_SECTION("nu " << nu << " P" << degree) {
        auto mean = disk_problem(make_neo_hookean_mean_dilatation(E, nu), degree);
        auto pointwise = disk_problem(make_neo_hookean(E, nu), degree);
        // Unconstrained twins for the homogeneous deformation (a patch would pin its nodes).
        auto free_body = [&](EffectPtr material) {
          std::vector<EffectPtr> effects;
          effects.push_back(std::move(material));
          return std::make_unique<Problem>(PETSC_COMM_WORLD, hstest::disk_mesh(0.2), std::move(effects),
                                           hstest::degree(degree));
        };
        auto mean_free = free_body(make_neo_hookean_mean_dilatation(E, nu));
        auto pointwise_free = free_body(make_neo_hookean(E, nu));
        core::VecH u = mean->create_vector(), v = mean->create_vector(), affine = mean_free->create_vector();
        hstest::interpolate(*mean, [](const double* x, double* f) { smooth_field(x, f, 0.5); }, u);
        hstest::interpolate(*mean, [](const double* x, double* f) {
          f[0] = 0.1 * x[1] * x[1] + 0.05;
          f[1] = -0.2 * x[0] * x[1];
        }, v);
        REQUIRE(mean->min_det_f(u) < 0.99);
        check_consistency(*mean, u, v);
        // A homogeneous deformation (J the same everywhere) and, on P1, any field (J constant per
        // cell): theta_e = J, the pointwise Neo-Hookean's residual and energy.
        hstest::interpolate(*mean_free, [](const double* x, double* f) {
          f[0] = 0.08 * x[0] - 0.05 * x[1];
          f[1] = 0.03 * x[0] - 0.06 * x[1];
        }, affine);
        auto same = [&](const Problem& a, const Problem& b, Vec w) {
          CHECK(hstest::rel_diff(residual(a, w), residual(b, w)) < 1e-12);
          double ea = 0, eb = 0;
          REQUIRE(a.energy(w, 0.0, ea));
          REQUIRE(b.energy(w, 0.0, eb));
          CHECK(ea == Approx(eb).epsilon(1e-12));
        };
        same(*mean_free, *pointwise_free, affine);
        if (degree == 1) same(*mean, *pointwise, u);
        // On P2 a non-affine field's J varies within cells: the energies differ.
        if (degree == 2) CHECK(hstest::rel_diff(residual(*mean, u), residual(*pointwise, u)) > 1e-4);
      }
    }
}

TEST_CASE("Mean dilatation with a pointwise share: the blend of the two materials, consistent",
          "[assembly][materials][mean_dilatation]") {
  // b lambda on the pointwise dilatation, (1 - b) lambda on the cell means: energy and residual
  // are exactly (1 - b) (mean) + b (pointwise), the shear part being common to both.
  const double nu = 0.49, b = 0.3;
  auto blend = disk_problem(make_neo_hookean_mean_dilatation(E, nu, {}, b), 2);
  auto mean = disk_problem(make_neo_hookean_mean_dilatation(E, nu), 2);
  auto pointwise = disk_problem(make_neo_hookean(E, nu), 2);
  core::VecH u = blend->create_vector(), v = blend->create_vector();
  hstest::interpolate(*blend, [](const double* x, double* f) { smooth_field(x, f, 0.5); }, u);
  hstest::interpolate(*blend, [](const double* x, double* f) {
    f[0] = 0.1 * x[1] * x[1] + 0.05;
    f[1] = -0.2 * x[0] * x[1];
  }, v);
  check_consistency(*blend, u, v);
  double e_blend = 0, e_mean = 0, e_pw = 0;
  REQUIRE(blend->energy(u, 0.0, e_blend));
  REQUIRE(mean->energy(u, 0.0, e_mean));
  REQUIRE(pointwise->energy(u, 0.0, e_pw));
  CHECK(e_blend == Approx((1 - b) * e_mean + b * e_pw).epsilon(1e-12));
  core::VecH r = blend->create_vector(), rm = blend->create_vector(), rp = blend->create_vector();
  REQUIRE(blend->residual(u, 0.0, r));
  REQUIRE(mean->residual(u, 0.0, rm));
  REQUIRE(pointwise->residual(u, 0.0, rp));
  HS_PETSC(VecAXPBY(rm, b, 1 - b, rp));  // rm = (1 - b) rm + b rp
  CHECK(hstest::rel_diff(r, rm) < 1e-12);
  CHECK(hstest::rel_diff(r, rp) > 1e-4);  // and it is neither of them
}

}  // namespace test_materials
