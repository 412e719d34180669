/// Pointwise Neo-Hookean kernel: stress = dW/dF and tangent = dP/dF by finite differences,
/// stress-free reference state, the linear-elastic limit, objectivity and the det F <= 0 guard.
#include <catch2/catch.hpp>
#include <cmath>
#include <random>

#include "hypershape/physics/neo_hookean.hpp"
#include "support/kernel_checks.hpp"

using namespace hypershape::physics;

// Named for the unity build (HS_UNITY_BUILD): files of one batch share a scope.
namespace test_neo_hookean {
namespace {

constexpr double E = 500.0, NU = 0.3;

template <int D>
NeoHookean<D> material(double nu = NU) {
  const Lame l = Lame::from_young_poisson(E, nu);
  return {l.mu, l.lambda};
}

using hstest::fd4;
using hstest::random_f;
using hstest::random_rotation;

template <int D>
void check_derivatives() {
  std::mt19937_64 rng(1234 + D);
  for (double nu : {0.3, 0.49}) {
    const auto m = material<D>(nu);
    for (int sample = 0; sample < 8; ++sample) {
      const Tensor<D> F = random_f<D>(rng);
      INFO("D = " << D << ", nu = " << nu << ", sample " << sample << ", F =\n" << F);
      Tensor<D> P;
      Tangent<D> A;
      double W;
      REQUIRE(m.energy(F, W));
      REQUIRE(m.stress(F, P));
      Tensor<D> P2;
      REQUIRE(m.stress_tangent(F, P2, A));
      CHECK((P2 - P).norm() <= 1e-14 * P.norm());

      const double h = 1e-4;
      Tensor<D> P_fd;
      Tangent<D> A_fd;
      for (int k = 0; k < D; ++k)
        for (int l = 0; l < D; ++l) {
          P_fd(k, l) = fd4<D>(
              [&](const Tensor<D>& G) {
                double w = 0;
                m.energy(G, w);
                return w;
              },
              F, k, l, h);
          const Tensor<D> dP = fd4<D>(
              [&](const Tensor<D>& G) {
                Tensor<D> p;
                m.stress(G, p);
                return Tensor<D>(p);
              },
              F, k, l, h);
          for (int i = 0; i < D; ++i)
            for (int J = 0; J < D; ++J) A_fd(i * D + J, k * D + l) = dP(i, J);
        }
      CHECK((P - P_fd).norm() <= 1e-6 * P.norm());
      CHECK((A - A_fd).norm() <= 1e-6 * A.norm());
      // Hyperelastic: the tangent has major symmetry.
      CHECK((A - A.transpose()).norm() <= 1e-12 * A.norm());
    }
  }
}

template <int D>
void check_reference_state() {
  const auto m = material<D>();
  const Tensor<D> I = Tensor<D>::Identity();
  double W = 1.0;
  Tensor<D> P;
  Tangent<D> A;
  REQUIRE(m.energy(I, W));
  REQUIRE(m.stress_tangent(I, P, A));
  CHECK(std::abs(W) <= 1e-14 * E);
  CHECK(P.norm() <= 1e-13 * E);
  // Linearisation at F = I is isotropic linear elasticity:
  // C_iJkL = lambda d_iJ d_kL + mu (d_ik d_JL + d_iL d_Jk).
  const Lame l = Lame::from_young_poisson(E, NU);
  Tangent<D> C;
  for (int i = 0; i < D; ++i)
    for (int J = 0; J < D; ++J)
      for (int k = 0; k < D; ++k)
        for (int L = 0; L < D; ++L)
          C(i * D + J, k * D + L) =
              l.lambda * (i == J) * (k == L) + l.mu * ((i == k) * (J == L) + (i == L) * (J == k));
  CHECK((A - C).norm() <= 1e-12 * C.norm());
}

template <int D>
void check_objectivity() {
  std::mt19937_64 rng(99 + D);
  const auto m = material<D>();
  for (int sample = 0; sample < 8; ++sample) {
    const Tensor<D> F = random_f<D>(rng), Q = random_rotation<D>(rng);
    REQUIRE(std::abs(Q.determinant() - 1.0) < 1e-12);
    REQUIRE((Q.transpose() * Q - Tensor<D>::Identity()).norm() < 1e-12);
    double W = 0, WQ = 0;
    Tensor<D> P, PQ;
    REQUIRE(m.energy(F, W));
    REQUIRE(m.energy(Q * F, WQ));
    REQUIRE(m.stress(F, P));
    REQUIRE(m.stress(Q * F, PQ));
    CHECK(std::abs(WQ - W) <= 1e-12 * std::abs(W));
    CHECK((PQ - Q * P).norm() <= 1e-12 * P.norm());
    // A rigid rotation alone stores no energy and no stress.
    double WR = 0;
    Tensor<D> PR;
    REQUIRE(m.energy(Q, WR));
    REQUIRE(m.stress(Q, PR));
    CHECK(std::abs(WR) <= 1e-12 * E);
    CHECK(PR.norm() <= 1e-12 * E);
  }
}

template <int D>
void check_guard() {
  const auto m = material<D>();
  Tensor<D> reflect = Tensor<D>::Identity();
  reflect(0, 0) = -1.0;
  Tensor<D> singular = Tensor<D>::Identity();
  singular(D - 1, D - 1) = 0.0;
  Tensor<D> nan_f = Tensor<D>::Identity();
  nan_f(0, 1) = std::nan("");
  for (const Tensor<D>& F : {reflect, Tensor<D>(0.5 * reflect), singular, nan_f}) {
    INFO("F =\n" << F);
    double W = 42.0;
    Tensor<D> P = Tensor<D>::Constant(7.0), P0 = P;
    Tangent<D> A = Tangent<D>::Constant(3.0), A0 = A;
    CHECK_FALSE(m.energy(F, W));
    CHECK_FALSE(m.stress(F, P));
    CHECK_FALSE(m.stress_tangent(F, P, A));
    // Outputs are left untouched.
    CHECK(W == 42.0);
    CHECK(P == P0);
    CHECK(A == A0);
  }
}

}  // namespace

TEST_CASE("Lame parameters from E and nu", "[kernel]") {
  const Lame l = Lame::from_young_poisson(500.0, 0.3);
  CHECK(l.mu == Approx(500.0 / 2.6).epsilon(1e-14));
  CHECK(l.lambda == Approx(500.0 * 0.3 / (1.3 * 0.4)).epsilon(1e-14));
}

TEST_CASE("Neo-Hookean energy has the closed form on a diagonal stretch", "[kernel]") {
  const auto m = material<3>();
  const double a = 1.3, b = 0.8, c = 1.1, J = a * b * c;
  Tensor<3> F = Tensor<3>::Zero();
  F.diagonal() << a, b, c;
  const double expected = 0.5 * m.mu * (a * a + b * b + c * c - 3 - 2 * std::log(J)) +
                          0.5 * m.lambda * std::log(J) * std::log(J);
  double W;
  REQUIRE(m.energy(F, W));
  CHECK(W == Approx(expected).epsilon(1e-14));
  // Plane strain: the 2D energy is the 3D energy with F_33 = 1.
  const auto m2 = material<2>();
  Tensor<2> F2 = Tensor<2>::Zero();
  F2.diagonal() << a, b;
  Tensor<3> F3 = Tensor<3>::Identity();
  F3.topLeftCorner<2, 2>() = F2;
  double W2 = 0, W3 = 0;
  REQUIRE(m2.energy(F2, W2));
  REQUIRE(m.energy(F3, W3));
  CHECK(W2 == Approx(W3).epsilon(1e-14));
}

TEST_CASE("Neo-Hookean stress and tangent match finite differences", "[kernel]") {
  SECTION("2D") { check_derivatives<2>(); }
  SECTION("3D") { check_derivatives<3>(); }
}

TEST_CASE("Neo-Hookean reference state is stress free with the linear-elastic tangent",
          "[kernel]") {
  SECTION("2D") { check_reference_state<2>(); }
  SECTION("3D") { check_reference_state<3>(); }
}

TEST_CASE("Neo-Hookean is objective", "[kernel]") {
  SECTION("2D") { check_objectivity<2>(); }
  SECTION("3D") { check_objectivity<3>(); }
}

TEST_CASE("Neo-Hookean refuses det F <= 0", "[kernel]") {
  SECTION("2D") { check_guard<2>(); }
  SECTION("3D") { check_guard<3>(); }
}

}  // namespace test_neo_hookean
