/// Manufactured finite-strain solution: u* = A_i prod_j sin(k_ij pi x_j) on the unit square /
/// cube, clamped on the whole boundary, with the body force b = -Div P(I + grad u*) computed
/// analytically from the kernel's tangent: (Div P)_i = A_iJkL d^2 u*_k / dX_L dX_J. The L2 error
/// (cell quadrature of degree 2p + 2) must fall like h^(p+1).
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "hypershape/physics/neo_hookean.hpp"
#include "hypershape/solver/nonlinear.hpp"
#include "support/helpers.hpp"

using namespace hypershape;

// Named for the unity build (HS_UNITY_BUILD): files of one batch share a scope.
namespace test_mms {
namespace {

constexpr double pi = std::numbers::pi;
constexpr double E = 500.0;

template <int D>
struct Manufactured {
  double A[D];
  int k[D][D];

  double s(int i, int j, const double* x) const { return std::sin(k[i][j] * pi * x[j]); }
  double c(int i, int j, const double* x) const { return std::cos(k[i][j] * pi * x[j]); }

  void value(const double* x, double* u) const {
    for (int i = 0; i < D; ++i) {
      u[i] = A[i];
      for (int j = 0; j < D; ++j) u[i] *= s(i, j, x);
    }
  }
  /// G(i, m) = d u_i / d x_m
  physics::Tensor<D> gradient(const double* x) const {
    physics::Tensor<D> G;
    for (int i = 0; i < D; ++i)
      for (int m = 0; m < D; ++m) {
        double v = A[i] * k[i][m] * pi * c(i, m, x);
        for (int j = 0; j < D; ++j)
          if (j != m) v *= s(i, j, x);
        G(i, m) = v;
      }
    return G;
  }
  /// d^2 u_i / dx_m dx_n
  double hessian(int i, int m, int n, const double* x) const {
    double v = A[i];
    if (m == n) {
      v *= -(k[i][m] * pi) * (k[i][m] * pi);
      for (int j = 0; j < D; ++j) v *= s(i, j, x);
    } else {
      v *= k[i][m] * pi * k[i][n] * pi * c(i, m, x) * c(i, n, x);
      for (int j = 0; j < D; ++j)
        if (j != m && j != n) v *= s(i, j, x);
    }
    return v;
  }
  /// b = -Div P(I + grad u*); returns false if det F <= 0 at x.
  bool body_force(const physics::NeoHookean<D>& m, const double* x, double* b) const {
    const physics::Tensor<D> F = physics::Tensor<D>::Identity() + gradient(x);
    physics::Tensor<D> P;
    physics::Tangent<D> At;
    if (!m.stress_tangent(F, P, At)) return false;
    for (int i = 0; i < D; ++i) {
      double div = 0;
      for (int J = 0; J < D; ++J)
        for (int kk = 0; kk < D; ++kk)
          for (int L = 0; L < D; ++L) div += At(i * D + J, kk * D + L) * hessian(kk, L, J, x);
      b[i] = -div;
    }
    return true;
  }
};

template <int D>
Manufactured<D> solution();
template <>
Manufactured<2> solution<2>() {
  return {{0.12, 0.06}, {{1, 1}, {2, 1}}};
}
template <>
Manufactured<3> solution<3>() {
  return {{0.12, 0.06, 0.06}, {{1, 1, 1}, {1, 2, 1}, {2, 1, 1}}};
}

struct Level {
  double h_target, h_effective, error, min_det_f;
  int newton;
};

template <int D>
std::vector<Level> convergence_study(int degree, const std::vector<double>& hs, double nu,
                                     double scale) {
  Manufactured<D> ms = solution<D>();
  for (double& a : ms.A) a *= scale;
  const physics::Lame l = physics::Lame::from_young_poisson(E, nu);
  const physics::NeoHookean<D> mat{l.mu, l.lambda};
  std::vector<Level> out;
  for (double h : hs) {
    std::vector<physics::EffectPtr> effects;
    effects.push_back(physics::make_neo_hookean(E, nu));
    effects.push_back(physics::make_dirichlet("clamp", hstest::everywhere()));
    bool admissible = true;
    effects.push_back(
        physics::make_body_force([&ms, &mat, &admissible](const double* x, double* b) {
          admissible = ms.body_force(mat, x, b) && admissible;
        }));
    physics::SpaceOptions so;
    so.degree = degree;
    so.quadrature_degree = 2 * degree + 2;
    physics::Problem problem(PETSC_COMM_WORLD, mesh::mesh_box(D, 1.0, h), std::move(effects), so);
    REQUIRE(admissible);
    REQUIRE(hstest::domain_measure(problem) == Approx(1.0).epsilon(1e-12));

    solver::SolverOptions opt;
    opt.rtol = 1e-11;
    solver::NonlinearSolver ns(problem, opt);
    const solver::SolveResult r = ns.solve(1.0);
    INFO("h = " << h << ": " << r.reason);
    REQUIRE(r.converged);
    const auto exact = [&ms](const double* x, double* u) { ms.value(x, u); };
    Level lv;
    lv.h_target = h;
    lv.h_effective = std::pow(1.0 / double(problem.space().n_cells_global()), 1.0 / D);
    lv.error = hstest::l2_error(problem, ns.solution(), exact);
    lv.min_det_f = problem.min_det_f(ns.solution());
    lv.newton = r.newton_iterations;
    out.push_back(lv);
  }
  return out;
}

/// Checks the observed rate between the two finest meshes, prints the table.
/// `scale` shrinks the manufactured amplitude (nearly incompressible runs: J = 0.6 at nu = 0.49
/// would mean a pressure of about 20 mu, far outside the regime the solver is tuned for).
template <int D>
void check_rates(int degree, const std::vector<double>& hs, double min_rate, double nu = 0.3,
                 double scale = 1.0) {
  const auto lv = convergence_study<D>(degree, hs, nu, scale);
  Manufactured<D> ms = solution<D>();
  for (double& a : ms.A) a *= scale;
  // Size of the solution, to make "the error is small" meaningful.
  const double u_norm = [&] {
    double n2 = 1.0;  // int sin^2(k pi x) over [0,1] = 1/2 per factor
    for (int j = 0; j < D; ++j) n2 *= 0.5;
    double s = 0;
    for (int i = 0; i < D; ++i) s += ms.A[i] * ms.A[i] * n2;
    return std::sqrt(s);
  }();
  std::printf("MMS %dD P%d nu = %g (||u*||_L2 = %.4g)\n  %-8s %-10s %-12s %-8s %-8s %s\n", D,
              degree, nu, u_norm, "h", "h_eff", "L2 error", "rate", "min J", "Newton");
  for (std::size_t i = 0; i < lv.size(); ++i) {
    const double rate = i ? std::log(lv[i - 1].error / lv[i].error) /
                                std::log(lv[i - 1].h_effective / lv[i].h_effective)
                          : 0.0;
    std::printf("  %-8.4g %-10.4g %-12.4e %-8.3f %-8.4f %d\n", lv[i].h_target, lv[i].h_effective,
                lv[i].error, rate, lv[i].min_det_f, lv[i].newton);
  }
  std::fflush(stdout);
  const std::size_t n = lv.size();
  REQUIRE(n >= 3);
  // Finite strain indeed: the manufactured state is far from the reference one.
  CHECK(lv[n - 1].min_det_f < 1.0 - 0.1 * scale);
  const double rate = std::log(lv[n - 2].error / lv[n - 1].error) /
                      std::log(lv[n - 2].h_effective / lv[n - 1].h_effective);
  const double rate_nominal = std::log2(lv[n - 2].error / lv[n - 1].error);
  INFO("rate on the two finest meshes: " << rate << " (per halving of h: " << rate_nominal << ")");
  CHECK(rate > min_rate);
  CHECK(rate_nominal > min_rate);
  // A much faster "rate" means the coarser error was spurious (a wrong equilibrium branch was
  // seen that way). The margin is wide because 3D meshes vary from run to run (HXT) and the
  // h = 1/8 error with them by up to 50%.
  CHECK(rate < degree + 3.0);
  // Errors fall monotonically and the finest is small relative to the solution.
  for (std::size_t i = 1; i < n; ++i) CHECK(lv[i].error < lv[i - 1].error);
  CHECK(lv[n - 1].error < (degree == 1 ? 0.05 : 0.01) * u_norm);
}

}  // namespace

TEST_CASE("MMS 2D P1 converges at order 2", "[mms]") {
  check_rates<2>(1, {1.0 / 4, 1.0 / 8, 1.0 / 16, 1.0 / 32}, 1.8);
}

TEST_CASE("MMS 2D P2 converges at order 3", "[mms]") {
  check_rates<2>(2, {1.0 / 4, 1.0 / 8, 1.0 / 16, 1.0 / 32}, 2.7);
}

TEST_CASE("MMS 3D P1 converges at order 2", "[mms][mms3d]") {
  check_rates<3>(1, {1.0 / 4, 1.0 / 8, 1.0 / 16}, 1.8);
}

TEST_CASE("MMS 3D P2 converges at order 3", "[mms][mms3d]") {
  check_rates<3>(2, {1.0 / 4, 1.0 / 8, 1.0 / 16}, 2.7);
}

TEST_CASE("MMS 2D P2 converges at order 3 when nearly incompressible", "[mms]") {
  check_rates<2>(2, {1.0 / 4, 1.0 / 8, 1.0 / 16, 1.0 / 32}, 2.7, 0.49, 0.4);
}

TEST_CASE("MMS 3D P2 converges at order 3 when nearly incompressible", "[mms][mms3d]") {
  check_rates<3>(2, {1.0 / 4, 1.0 / 8, 1.0 / 16}, 2.7, 0.49, 0.25);
}

TEST_CASE("MMS 3D P1 converges at order 2 on finer meshes", "[mms][mms3d][slow]") {
  check_rates<3>(1, {1.0 / 8, 1.0 / 16, 1.0 / 32}, 1.8);
}

}  // namespace test_mms
