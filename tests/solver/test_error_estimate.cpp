/// The labels' error estimate (solver::TwoLevelEstimator, mesh::refine_uniform):
///  - the refinement is nested and the prolongation exact (P1 and P2 fields of the coarse
///    space are reproduced at every fine node);
///  - a solution the space contains (the homogeneous deformation of the unit square under a
///    uniform dead traction) has a zero estimate (round-off);
///  - on the manufactured finite-strain solution of test_mms (smooth: the error falls like
///    h^(p+1), so -error_estimate_order p+1) the estimate falls at that rate and stays within
///    [0.5, 2] of the true error;
///  - a field with det F <= 0 between the coarse quadrature points is flagged (inverted);
///  - a local relaxation before the first fine step is always followed by a global one.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "hypershape/mesh/refine.hpp"
#include "hypershape/solver/error_estimate.hpp"
#include "hypershape/physics/neo_hookean.hpp"
#include "support/helpers.hpp"

using namespace hypershape;

namespace {

constexpr double pi = std::numbers::pi;

using EffectsMaker = std::function<std::vector<physics::EffectPtr>()>;

struct Pair {
  mesh::RefinedMesh refined;
  std::unique_ptr<physics::Problem> coarse, fine;
  std::unique_ptr<solver::TwoLevelEstimator> est;
};

Pair make_pair(const mesh::MeshData& m, int degree, const EffectsMaker& effects) {
  Pair p;
  p.refined = mesh::refine_uniform(m);
  physics::SpaceOptions so = hstest::degree(degree);
  p.coarse = std::make_unique<physics::Problem>(PETSC_COMM_WORLD, m, effects(), so);
  p.fine = std::make_unique<physics::Problem>(PETSC_COMM_WORLD, p.refined.mesh, effects(), so);
  p.est = std::make_unique<solver::TwoLevelEstimator>(*p.coarse, *p.fine, p.refined);
  return p;
}

/// The unit square clamped at x = 0 under a Gaussian downward traction on y = 1 (nu 0.45).
std::vector<physics::EffectPtr> clamped_box_effects() {
  std::vector<physics::EffectPtr> e;
  e.push_back(physics::make_neo_hookean(500, 0.45));
  e.push_back(physics::make_dirichlet("clamp", hstest::on_plane(0, 0.0), {0, 1}));
  e.push_back(physics::make_surface_traction(
      [](const double* x, double* t) { t[0] = 0, t[1] = -std::exp(-20 * (x[0] - 0.8) * (x[0] - 0.8)); },
      hstest::on_plane(1, 1.0)));
  return e;
}

/// u* of test_mms (2D): (0.12 sin(pi x) sin(pi y), 0.06 sin(2 pi x) sin(pi y)) and its body force
/// for the Neo-Hookean material (E 500, nu 0.3).
struct Mms {
  physics::NeoHookean<2> mat{physics::Lame::from_young_poisson(500, 0.3).mu,
                             physics::Lame::from_young_poisson(500, 0.3).lambda};
  double A[2] = {0.12, 0.06};
  int k[2][2] = {{1, 1}, {2, 1}};
  void value(const double* x, double* u) const {
    for (int i = 0; i < 2; ++i) u[i] = A[i] * std::sin(k[i][0] * pi * x[0]) * std::sin(k[i][1] * pi * x[1]);
  }
  void body_force(const double* x, double* b) const {
    physics::Tensor<2> G;
    double H[2][2][2];
    for (int i = 0; i < 2; ++i) {
      const double a = k[i][0] * pi, c = k[i][1] * pi, sx = std::sin(a * x[0]), sy = std::sin(c * x[1]),
                   cx = std::cos(a * x[0]), cy = std::cos(c * x[1]);
      G(i, 0) = A[i] * a * cx * sy, G(i, 1) = A[i] * c * sx * cy;
      H[i][0][0] = -A[i] * a * a * sx * sy, H[i][1][1] = -A[i] * c * c * sx * sy;
      H[i][0][1] = H[i][1][0] = A[i] * a * c * cx * cy;
    }
    physics::Tensor<2> P;
    physics::Tangent<2> At;
    const physics::Tensor<2> F = physics::Tensor<2>::Identity() + G;
    REQUIRE(mat.stress_tangent(F, P, At));
    for (int i = 0; i < 2; ++i) {
      b[i] = 0;
      for (int J = 0; J < 2; ++J)
        for (int kk = 0; kk < 2; ++kk)
          for (int L = 0; L < 2; ++L) b[i] -= At(i * 2 + J, kk * 2 + L) * H[kk][L][J];
    }
  }
};

}  // namespace

TEST_CASE("Uniform refinement is nested and the prolongation exact", "[error_estimate]") {
  for (int dim : {2, 3})
    for (int deg : {1, 2}) {
      DYNAMIC_SECTION(dim << "D P" << deg) {
        const mesh::MeshData m = mesh::mesh_box(dim, 1.0, dim == 2 ? 0.3 : 0.6);
        auto effects = [dim] {
          std::vector<physics::EffectPtr> e;
          e.push_back(physics::make_neo_hookean(500, 0.3));
          e.push_back(physics::make_dirichlet("clamp", hstest::on_plane(0, 0.0)));
          (void)dim;
          return e;
        };
        Pair p = make_pair(m, deg, effects);
        CHECK(p.refined.mesh.n_cells() == m.n_cells() * (dim == 2 ? 4 : 8));
        CHECK(hstest::domain_measure(*p.fine) == Approx(1.0).epsilon(1e-12));
        CHECK(p.fine->space().min_det_jacobian() > 0);
        // A field of the space (linear for P1, quadratic for P2) that vanishes on the clamped
        // face x = 0: the prolonged coarse interpolant must equal the fine interpolant at every
        // fine node.
        auto f = [deg](const double* x, double* u) {
          const double q = deg == 2 ? 1.0 : 0.0;
          u[0] = x[0] * (0.3 + q * (0.5 * x[1] - 0.2 * x[0]));
          u[1] = x[0] * (-0.4 + q * 0.25 * x[1]);
          u[2] = x[0] * (0.2 + q * 0.3 * x[0]);
        };
        core::VecH uc = p.coarse->create_vector(), uf = p.fine->create_vector();
        hstest::interpolate(*p.coarse, f, uc);
        hstest::interpolate(*p.fine, f, uf);
        const auto prolonged = p.est->prolong(p.coarse->gather(uc).values);
        const auto direct = p.fine->gather(uf).values;
        REQUIRE(prolonged.size() == direct.size());
        double worst = 0;
        for (std::size_t i = 0; i < direct.size(); ++i) worst = std::max(worst, std::abs(prolonged[i] - direct[i]));
        CHECK(worst < 1e-13);
      }
    }
}

TEST_CASE("The L2 norm of a field of the space is its exact integral", "[error_estimate]") {
  // On the unit box: P1 u = (x, y + 1, z - x), P2 u = (x^2 + y, x y, z^2 - x), integrated by hand.
  for (int dim : {2, 3})
    for (int deg : {1, 2}) {
      DYNAMIC_SECTION(dim << "D P" << deg) {
        const mesh::MeshData m = mesh::mesh_box(dim, 1.0, dim == 2 ? 0.3 : 0.6);
        std::vector<physics::EffectPtr> effects;
        effects.push_back(physics::make_neo_hookean(500, 0.3));
        physics::Problem problem(PETSC_COMM_WORLD, m, std::move(effects), hstest::degree(deg));
        auto f = [deg](const double* x, double* u) {
          u[0] = deg == 1 ? x[0] : x[0] * x[0] + x[1];
          u[1] = deg == 1 ? x[1] + 1 : x[0] * x[1];
          u[2] = deg == 1 ? x[2] - x[0] : x[2] * x[2] - x[0];
        };
        core::VecH u = problem.create_vector();
        hstest::interpolate(problem, f, u);
        const std::vector<double> values = problem.gather(u).values;
        if (values.empty()) return;  // (rank > 0)
        const auto& s = problem.space();
        const double exact = deg == 1 ? (dim == 2 ? 8.0 / 3 : 17.0 / 6) : (dim == 2 ? 44.0 / 45 : 53.0 / 45);
        CHECK(solver::l2_norm_squared(dim, deg, s.canonical_coords(), s.canonical_cells(), values, dim) ==
              Approx(exact).epsilon(1e-13));
      }
    }
}

TEST_CASE("The estimate of a solution the space contains is zero", "[error_estimate]") {
  for (int deg : {1, 2}) {
    DYNAMIC_SECTION("2D P" << deg) {
      const double T = 40.0;  // a finite stretch of the Neo-Hookean square
      auto effects = [T] {
        std::vector<physics::EffectPtr> e;
        e.push_back(physics::make_neo_hookean(500, 0.3));
        e.push_back(physics::make_dirichlet("roller_x", hstest::on_plane(0, 0.0), {0}));
        e.push_back(physics::make_dirichlet("roller_y", hstest::on_plane(1, 0.0), {1}));
        e.push_back(physics::make_surface_traction([T](const double*, double* t) { t[0] = T, t[1] = 0; },
                                                   hstest::on_plane(0, 1.0)));
        return e;
      };
      Pair p = make_pair(mesh::mesh_box(2, 1.0, 0.25), deg, effects);
      solver::SolverOptions so;
      so.rtol = 1e-12;
      solver::NonlinearSolver ns(*p.coarse, so);
      REQUIRE(ns.solve(1.0).converged);
      REQUIRE(p.coarse->max_displacement(ns.solution()) > 0.05);
      const solver::ErrorEstimate e = p.est->estimate(ns.solution(), 1.0);
      REQUIRE(e.ok);
      INFO("rel_l2 " << e.rel_l2 << " max_u " << e.max_u << " alpha " << e.alpha);
      CHECK(e.rel_l2 < 1e-9);
      CHECK(std::abs(e.max_u) < 1e-9);
      CHECK(std::abs(e.alpha) < 1e-9);
      CHECK(e.krylov_iterations >= 0);
    }
  }
}

TEST_CASE("The estimate of the manufactured solution converges at the L2 rate", "[error_estimate]") {
  const Mms ms;
  for (int deg : {1, 2}) {
    DYNAMIC_SECTION("2D P" << deg) {
      std::vector<double> est, truth;
      const std::vector<double> hs = deg == 1 ? std::vector<double>{1.0 / 8, 1.0 / 16, 1.0 / 32}
                                              : std::vector<double>{1.0 / 4, 1.0 / 8, 1.0 / 16};
      HS_PETSC(PetscOptionsSetValue(nullptr, "-error_estimate_order", deg == 1 ? "2" : "3"));
      for (double h : hs) {
        auto effects = [&ms] {
          std::vector<physics::EffectPtr> e;
          e.push_back(physics::make_neo_hookean(500, 0.3));
          e.push_back(physics::make_dirichlet("clamp", hstest::everywhere()));
          e.push_back(physics::make_body_force([&ms](const double* x, double* b) { ms.body_force(x, b); }));
          return e;
        };
        Pair p = make_pair(mesh::mesh_box(2, 1.0, h), deg, effects);
        solver::SolverOptions so;
        so.rtol = 1e-11;
        solver::NonlinearSolver ns(*p.coarse, so);
        REQUIRE(ns.solve(1.0).converged);
        const auto e = p.est->estimate(ns.solution(), 1.0);
        REQUIRE(e.ok);
        core::VecH ue = p.coarse->create_vector();
        hstest::interpolate(*p.coarse, [&ms](const double* x, double* u) { ms.value(x, u); }, ue);
        const double u_norm = std::sqrt(0.25 * (ms.A[0] * ms.A[0] + ms.A[1] * ms.A[1]));
        est.push_back(e.rel_l2);
        truth.push_back(hstest::l2_error(*p.coarse, ns.solution(), [&ms](const double* x, double* u) { ms.value(x, u); }) /
                        u_norm);
        std::printf("P%d h %-8.4g estimate %-10.4e true %-10.4e effectivity %.3f (CG %d its)\n", deg, h, est.back(),
                    truth.back(), est.back() / truth.back(), e.krylov_iterations);
      }
      HS_PETSC(PetscOptionsClearValue(nullptr, "-error_estimate_order"));
      const std::size_t n = est.size();
      const double rate = std::log2(est[n - 2] / est[n - 1]);
      INFO("estimate rate " << rate);
      CHECK(rate > deg + 1 - 0.3);
      CHECK(rate < deg + 1 + 0.5);
      for (std::size_t i = 0; i < n; ++i) {
        CHECK(est[i] / truth[i] > 0.5);
        CHECK(est[i] / truth[i] < 2.0);
      }
    }
  }
}

TEST_CASE("The estimate on the solver's factor is the estimate on its own", "[error_estimate]") {
  // The factory passes the nonlinear solver's factor as the coarse level (a tangent one Newton
  // step before u_h); the estimator's own factorisation of K_c(u_h) must give the same estimate
  // up to the fine solve's tolerance, and without a factor the estimate says so (ok = false).
  const EffectsMaker effects = clamped_box_effects;
  Pair p = make_pair(mesh::mesh_box(2, 1.0, 0.125), 1, effects);
  solver::NonlinearSolver fresh(*p.coarse, solver::SolverOptions{});
  Vec x = p.coarse->load();
  core::VecH y = p.coarse->create_vector();
  CHECK_FALSE(fresh.apply_tangent_factor(x, y));  // nothing factorised yet
  solver::NonlinearSolver ns(*p.coarse, solver::SolverOptions{});
  const auto t = ns.solve_for_target(0.2);
  REQUIRE(t.converged);
  const solver::ErrorEstimate own = p.est->estimate(ns.solution(), t.alpha);
  const solver::ErrorEstimate kept =
      p.est->estimate(ns.solution(), t.alpha, [&](Vec b, Vec z, bool refined) { return ns.apply_tangent_factor(b, z, refined); });
  REQUIRE(own.ok);
  REQUIRE(kept.ok);
  INFO("own " << own.rel_l2 << " kept " << kept.rel_l2 << " its " << own.krylov_iterations << " / " << kept.krylov_iterations);
  CHECK(own.rel_l2 > 1e-3);
  CHECK(std::abs(kept.rel_l2 / own.rel_l2 - 1) < 0.05);
  CHECK(std::abs(kept.alpha / own.alpha - 1) < 0.05);
  CHECK(own.factorizations == 1);
  CHECK(kept.factorizations == 0);
  const solver::ErrorEstimate none =
      p.est->estimate(ns.solution(), t.alpha, [&](Vec b, Vec z, bool refined) { return fresh.apply_tangent_factor(b, z, refined); });
  CHECK_FALSE(none.ok);
}

TEST_CASE("Newton to tolerance on the fine mesh takes the steps one full step skips", "[error_estimate]") {
  // The mean-dilatation datasets ask for it (LabelErrorEstimator): there the first step mostly
  // restores the fine cells' volumes. On a smooth case both agree; the test is that the steps
  // are taken (a residual to 1% of the first) and that they stay at the same estimate.
  const EffectsMaker effects = clamped_box_effects;
  Pair p = make_pair(mesh::mesh_box(2, 1.0, 0.125), 2, effects);
  solver::TwoLevelEstimator to_tolerance(*p.coarse, *p.fine, p.refined, true);
  solver::NonlinearSolver ns(*p.coarse, solver::SolverOptions{});
  const auto t = ns.solve_for_target(0.2);
  REQUIRE(t.converged);
  const solver::ErrorEstimate one = p.est->estimate(ns.solution(), t.alpha);
  const solver::ErrorEstimate more = to_tolerance.estimate(ns.solution(), t.alpha);
  REQUIRE(one.ok);
  REQUIRE(more.ok);
  INFO("one step " << one.rel_l2 << ", to tolerance " << more.rel_l2 << " in " << more.tangent_assemblies << " steps");
  CHECK(more.tangent_assemblies > one.tangent_assemblies);  // here 3 against 2 (one step cut)
  CHECK(more.newton_steps_converged);
  CHECK(std::abs(more.rel_l2 / one.rel_l2 - 1) < 0.2);
  CHECK(std::abs(more.alpha / one.alpha - 1) < 0.2);
}

TEST_CASE("A fine step that spends its Krylov budget is kept", "[error_estimate]") {
  // The random3d preset's mean-dilatation tangents stop at the budget on a third of the steps
  // (docs/ACCURACY.md); GMRES's iterate is kept there, judged by the energy line search. Here a
  // budget of one iteration (the converged step takes more): an estimate all the same, flagged,
  // within a factor of the converged one. Without local relaxation, which here leaves the
  // Krylov solve a single iteration (the residual of P u_h sits at the clamp's corners).
  const hstest::ScopedOption no_relaxation("-error_estimate_no_relaxation");
  const EffectsMaker effects = clamped_box_effects;
  const auto m = mesh::mesh_box(2, 1.0, 0.125);
  Pair full = make_pair(m, 2, effects);
  solver::NonlinearSolver ns(*full.coarse, solver::SolverOptions{});
  const auto t = ns.solve_for_target(0.2);
  REQUIRE(t.converged);
  const solver::ErrorEstimate converged = full.est->estimate(ns.solution(), t.alpha);
  REQUIRE(converged.ok);
  REQUIRE(converged.krylov_iterations > 1);
  CHECK_FALSE(converged.krylov_budget_spent);
  HS_PETSC(PetscOptionsSetValue(nullptr, "-error_estimate_ksp_max_it", "1"));
  Pair capped = make_pair(m, 2, effects);  // its solver reads the option when first used
  const solver::ErrorEstimate one = capped.est->estimate(ns.solution(), t.alpha);
  HS_PETSC(PetscOptionsClearValue(nullptr, "-error_estimate_ksp_max_it"));
  INFO("converged " << converged.rel_l2 << " in " << converged.krylov_iterations << " its; budget 1: " << one.rel_l2);
  REQUIRE(one.ok);
  CHECK(one.krylov_budget_spent);
  CHECK(one.rel_l2 > 0.3 * converged.rel_l2);
  CHECK(one.rel_l2 < 3.0 * converged.rel_l2);
}

TEST_CASE("A local relaxation is followed by a global step, however far it lowers the residual", "[error_estimate]") {
  // The converged label with one interior node pushed off its equilibrium by delta: the fine
  // residual of P u_h then sits on that node's patch, which the local relaxation removes. Under a
  // small load (max|u| 0.02) the rest, the global error the unperturbed label's estimate
  // measures, is below 1% of the first residual for delta 0.01 and 0.02 (0.8% and 0.3%; not for
  // 0.005); the estimate must still take the fine Newton step that sees it. Until 2026-12-07 a
  // relaxation that met the estimator's 1% criterion ended the estimate, which then saw only the
  // relaxed node (checked: this test fails so, its states a whole correction apart; on Random2D one
  // label estimated 6e-7 where its neighbours had 4e-3).
  const EffectsMaker effects = clamped_box_effects;
  Pair p = make_pair(mesh::mesh_box(2, 1.0, 0.125), 2, effects);
  solver::NonlinearSolver ns(*p.coarse, solver::SolverOptions{});
  const auto t = ns.solve_for_target(0.02);
  REQUIRE(t.converged);
  const solver::ErrorEstimate plain = p.est->estimate(ns.solution(), t.alpha);
  REQUIRE(plain.ok);
  physics::NodalField u = p.coarse->gather(ns.solution());
  const std::vector<double>& xy = p.coarse->space().canonical_coords();
  std::size_t node = 0;  // the node nearest (0.5, 0.5)
  for (std::size_t i = 0; 2 * i < xy.size(); ++i)
    if (std::hypot(xy[2 * i] - 0.5, xy[2 * i + 1] - 0.5) < std::hypot(xy[2 * node] - 0.5, xy[2 * node + 1] - 0.5)) node = i;
  const double delta = GENERATE(0.005, 0.01, 0.02);
  u.values[2 * node] += delta;
  const core::VecH pushed = p.coarse->scatter(u.values);
  const solver::ErrorEstimate e = p.est->estimate(pushed, t.alpha);
  INFO("delta " << delta << ": unperturbed " << plain.rel_l2 << ", pushed " << e.rel_l2 << " after " << e.relaxations
                << " relaxations and " << e.tangent_assemblies << " fine tangents");
  REQUIRE(e.ok);
  CHECK(e.relaxations >= 1);
  CHECK(e.tangent_assemblies >= 2);  // the coarse tangent (the estimator factorises its own here) and a fine step
  // Both estimates end next to the fine equilibrium: their states differ by far less than the
  // global correction e of the unperturbed label (a relaxation alone leaves all of it out).
  REQUIRE(e.fine_state.size() == plain.fine_state.size());
  double diff = 0, norm = 0;
  for (std::size_t i = 0; i < e.fine_state.size(); ++i) {
    diff += std::pow(e.fine_state[i] - plain.fine_state[i], 2);
    norm += std::pow(plain.fine_state[i], 2);
  }
  INFO("states apart by " << std::sqrt(diff / norm) << " of |u|; the unperturbed correction " << plain.raw_rel_l2);
  CHECK(std::sqrt(diff / norm) < 0.3 * plain.raw_rel_l2);
}

TEST_CASE("A label that inverts inside a cell is flagged, not estimated", "[error_estimate]") {
  // u = (phi(x), 0) with phi' = x - x0 - 1: det F = x - x0, exactly linear in x (phi is in P2).
  // x0 below every quadrature point of the coarse cells but above the refined mesh's nearest
  // ones: the coarse problem accepts u (det F > 0 where it looks), the refined mesh sees it
  // inverted next to x = 0 -- what a mean-dilatation label does under a traction narrower than
  // its cells (docs/ACCURACY.md, "Labels that invert inside a cell").
  auto effects = [] {
    std::vector<physics::EffectPtr> e;
    e.push_back(physics::make_neo_hookean(500, 0.3));
    e.push_back(physics::make_dirichlet("roller_y", hstest::on_plane(1, 0.0), {1}));
    return e;
  };
  Pair p = make_pair(mesh::mesh_box(2, 1.0, 0.5), 2, effects);
  auto min_qp_x = [](const physics::Problem& pr) {
    const auto& s = pr.space();
    double m = INFINITY;
    for (PetscInt c = s.cell_begin(); c < s.cell_end(); ++c)
      for (int q = 0; q < s.n_qp(); ++q) {
        double x[3] = {0, 0, 0};
        s.map_point(c, q, x);
        m = std::min(m, x[0]);
      }
    double g = m;
    MPI_Allreduce(&m, &g, 1, MPI_DOUBLE, MPI_MIN, PETSC_COMM_WORLD);
    return g;
  };
  const double xc = min_qp_x(*p.coarse), xf = min_qp_x(*p.fine);
  REQUIRE(xf < 0.75 * xc);
  for (const double x0 : {0.75 * xc, -0.1}) {  // inverted next to x = 0; nowhere
    DYNAMIC_SECTION("x0 " << x0) {
      core::VecH u = p.coarse->create_vector();
      hstest::interpolate(*p.coarse, [x0](const double* x, double* v) {
        v[0] = 0.5 * (x[0] - x0) * (x[0] - x0) - x[0] - 0.5 * x0 * x0;
        v[1] = 0;
      }, u);
      REQUIRE(p.coarse->min_det_f(u) > 0);
      const solver::ErrorEstimate e = p.est->estimate(u, 0.0);
      CHECK(e.inverted == (x0 > 0));
      if (x0 > 0) CHECK_FALSE(e.ok);
    }
  }
}
