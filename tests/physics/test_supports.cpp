/// Supports beyond the clamp: the elastic (spring / Robin) foundation and the sliding support
/// (dirichlet with components). The spring's energy, residual and tangent are checked against
/// each other (energy derivative, finite differences, E = 1/2 u.K u), against a closed form for
/// a constant displacement, and in a bar on a normal spring under a uniform end traction, whose
/// exact solution is homogeneous (so P1 and P2 reproduce it to solver tolerance) in linear
/// elasticity and for Neo-Hookean at 20% stretch. The sliding support: a column on a sliding
/// base between sliding walls under its own weight (u_y quadratic: P2 exact) and a block on a
/// sliding base under a uniform top load (homogeneous uniaxial state).
#include <catch2/catch.hpp>
#include <cmath>
#include <random>

#include "hypershape/core/error.hpp"
#include "hypershape/physics/neo_hookean.hpp"
#include "hypershape/solver/nonlinear.hpp"
#include "support/helpers.hpp"

using namespace hypershape;
using core::MapParams;
using Vector = std::vector<double>;

namespace {

physics::EffectPtr effect(const char* name, MapParams p, int dim) { return physics::make_effect(name, p, dim); }

/// The unit square with a vertex at (0.5, 0): clamped on x = 1, a spring on y = 0, x <= 0.5.
std::unique_ptr<physics::Problem> square_on_spring(bool spring, double kn, double kt, int degree) {
  std::vector<physics::EffectPtr> e;
  e.push_back(physics::make_neo_hookean(100, 0.3));
  e.push_back(effect("dirichlet", MapParams({{"box", Vector{1, 0, 1, 1}}}), 2));
  if (spring) e.push_back(physics::make_spring(kn, kt, physics::Region::box({0, 0}, {0.5, 0})));
  const mesh::MeshData m = mesh::mesh_polygon({{0, 0}, {0.5, 0}, {1, 0}, {1, 1}, {0, 1}}, 0.15);
  return std::make_unique<physics::Problem>(PETSC_COMM_WORLD, m, std::move(e), hstest::degree(degree));
}

/// A 3D unit cube clamped on x = 1 with an isotropic spring on its face z = 0.
std::unique_ptr<physics::Problem> cube_on_spring(bool spring, double k, int degree) {
  std::vector<physics::EffectPtr> e;
  e.push_back(physics::make_neo_hookean(100, 0.3));
  e.push_back(effect("dirichlet", MapParams({{"box", Vector{1, 0, 0, 1, 1, 1}}}), 3));
  if (spring) e.push_back(effect("spring", MapParams({{"stiffness", k}, {"box", Vector{0, 0, 0, 1, 1, 0}}}), 3));
  return std::make_unique<physics::Problem>(PETSC_COMM_WORLD, mesh::mesh_box(3, 1.0, 0.35), std::move(e),
                                            hstest::degree(degree));
}

void random_vector(Vec v, unsigned seed, double scale) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> d(-scale, scale);
  PetscInt n;
  HS_PETSC(VecGetLocalSize(v, &n));
  PetscScalar* a;
  HS_PETSC(VecGetArray(v, &a));
  for (PetscInt i = 0; i < n; ++i) a[i] = d(rng);
  HS_PETSC(VecRestoreArray(v, &a));
}

/// The spring's part of energy, residual and tangent (problem with minus problem without; the
/// same mesh and constraints give the same layout), checked against each other.
void check_spring_part(const physics::Problem& with, const physics::Problem& without) {
  core::VecH u = with.create_vector(), v = with.create_vector(), r1 = with.create_vector(),
             r0 = with.create_vector(), Kv = with.create_vector(), rp = with.create_vector(),
             rm = with.create_vector(), w = with.create_vector();
  random_vector(u, 1, 0.01);
  random_vector(v, 2, 1.0);
  auto spring_energy = [&](Vec x) {
    double e1, e0;
    REQUIRE(with.energy(x, 0.0, e1));
    REQUIRE(without.energy(x, 0.0, e0));
    return e1 - e0;
  };
  auto spring_residual = [&](Vec x, Vec r) {
    REQUIRE(with.residual(x, 0.0, r));
    REQUIRE(without.residual(x, 0.0, r0));
    HS_PETSC(VecAXPY(r, -1.0, r0));
  };
  spring_residual(u, r1);
  PetscReal rnorm;
  HS_PETSC(VecNorm(r1, NORM_2, &rnorm));
  REQUIRE(rnorm > 0);  // the spring acts
  // E_s(u) = 1/2 u . r_s(u): the energy is quadratic and r_s = K u.
  PetscScalar ur;
  HS_PETSC(VecDot(u, r1, &ur));
  CHECK(spring_energy(u) == Approx(0.5 * PetscRealPart(ur)).epsilon(1e-10));
  // r_s = dE_s/du: central differences of a quadratic are exact up to rounding.
  const double h = 1e-3;
  HS_PETSC(VecWAXPY(w, h, v, u));
  const double ep = spring_energy(w);
  HS_PETSC(VecWAXPY(w, -h, v, u));
  const double em = spring_energy(w);
  PetscScalar vr;
  HS_PETSC(VecDot(v, r1, &vr));
  CHECK((ep - em) / (2 * h) == Approx(PetscRealPart(vr)).epsilon(1e-7));
  // The tangent (spring + material) against central differences of the full residual.
  core::MatH J = with.create_matrix();
  REQUIRE(with.jacobian(u, J));
  HS_PETSC(MatMult(J, v, Kv));
  const double hj = 1e-6;
  HS_PETSC(VecWAXPY(w, hj, v, u));
  REQUIRE(with.residual(w, 0.0, rp));
  HS_PETSC(VecWAXPY(w, -hj, v, u));
  REQUIRE(with.residual(w, 0.0, rm));
  HS_PETSC(VecAXPY(rp, -1.0, rm));
  HS_PETSC(VecScale(rp, 1.0 / (2 * hj)));
  INFO("|J v - FD| / |J v| = " << hstest::rel_diff(rp, Kv));
  CHECK(hstest::rel_diff(rp, Kv) < 1e-6);
}

/// max over nodes of |u - exact| (rank 0's view, broadcast).
double max_nodal_error(const physics::Problem& pb, Vec u, const hstest::Field& exact) {
  const physics::NodalField f = pb.gather(u);
  const auto& X = pb.space().canonical_coords();
  const int dim = pb.space().dim();
  double err = 0;
  for (std::size_t n = 0; n * std::size_t(dim) < f.values.size(); ++n) {
    double e[3] = {0, 0, 0};
    exact(&X[n * std::size_t(dim)], e);
    for (int i = 0; i < dim; ++i) err = std::max(err, std::abs(f.values[n * std::size_t(dim) + std::size_t(i)] - e[i]));
  }
  MPI_Bcast(&err, 1, MPI_DOUBLE, 0, PETSC_COMM_WORLD);
  return err;
}

Vec solve(const physics::Problem& pb, std::unique_ptr<solver::NonlinearSolver>& ns) {
  solver::SolverOptions so;
  so.rtol = 1e-12;
  ns = std::make_unique<solver::NonlinearSolver>(pb, so);
  const solver::SolveResult res = ns->solve(1.0);
  INFO("solver: " << res.reason << ", " << res.newton_iterations << " Newton iterations");
  REQUIRE(res.converged);
  return ns->solution();
}

}  // namespace

TEST_CASE("Spring: residual = energy derivative, tangent = finite differences, E = 1/2 u.K u", "[supports]") {
  for (int degree : {1, 2})
    for (auto [kn, kt] : {std::pair{50.0, 50.0}, std::pair{80.0, 0.0}, std::pair{0.0, 30.0}})
      DYNAMIC_SECTION("2D P" << degree << " k_n " << kn << " k_t " << kt) {
        check_spring_part(*square_on_spring(true, kn, kt, degree), *square_on_spring(false, kn, kt, degree));
      }
  for (int degree : {1, 2})
    DYNAMIC_SECTION("3D P" << degree) {
      check_spring_part(*cube_on_spring(true, 40.0, degree), *cube_on_spring(false, 40.0, degree));
    }
}

TEST_CASE("Spring: the energy of a constant displacement is 1/2 (k_n c_n^2 + k_t c_t^2) |Gamma|", "[supports]") {
  const double kn = 80.0, kt = 30.0, c[2] = {0.03, -0.02};
  for (int degree : {1, 2})
    DYNAMIC_SECTION("P" << degree) {
      auto with = square_on_spring(true, kn, kt, degree), without = square_on_spring(false, kn, kt, degree);
      core::VecH u = with->create_vector();
      hstest::interpolate(*with, [&](const double*, double* v) { v[0] = c[0], v[1] = c[1]; }, u);
      double e1, e0;
      REQUIRE(with->energy(u, 0.0, e1));
      REQUIRE(without->energy(u, 0.0, e0));
      // The edge y = 0, 0 <= x <= 0.5: N = -e_y, so c_n = c_y, c_t = c_x.
      CHECK(e1 - e0 == Approx(0.5 * (kn * c[1] * c[1] + kt * c[0] * c[0]) * 0.5).epsilon(1e-12));
    }
}

namespace {

/// Neo-Hookean plane strain P_1, P_2 at stretches (a, b, 1).
double nh_p(int i, double a, double b, const physics::Lame& m) {
  const double l[2] = {a, b};
  return m.mu * (l[i] - 1.0 / l[i]) + m.lambda * std::log(a * b) / l[i];
}

}  // namespace

TEST_CASE("A bar on a normal spring under an end traction: the closed form", "[supports]") {
  // [0, 2] x [0, 1], normal spring k_n on x = 0, sliding support (u_y = 0) on y = 0, traction
  // T e_x on x = 2. Homogeneous: F = diag(a, b), and the spring carries T: u_x(0) = T / k_n.
  const double E = 500, nu = 0.3, kn = 250, L = 2;
  const physics::Lame m = physics::Lame::from_young_poisson(E, nu);
  for (bool linear : {true, false})
    for (int degree : {1, 2})
      DYNAMIC_SECTION((linear ? "linear_elastic" : "neo_hookean") << " P" << degree) {
        double a, b, T;
        if (linear) {  // plane strain uniaxial stress T = 20
          T = 20;
          a = 1 + T * (1 - nu * nu) / E, b = 1 - T * nu * (1 + nu) / E;
        } else {  // a = 1.2, b from P_2 = 0 (bisection), T = P_1
          a = 1.2;
          double lo = 0.5, hi = 1.0;
          for (int it = 0; it < 200; ++it) ((nh_p(1, a, 0.5 * (lo + hi), m) > 0) ? hi : lo) = 0.5 * (lo + hi);
          b = 0.5 * (lo + hi), T = nh_p(0, a, b, m);
        }
        std::vector<physics::EffectPtr> e;
        e.push_back(linear ? physics::make_linear_elastic(E, nu) : physics::make_neo_hookean(E, nu));
        e.push_back(effect("spring", MapParams({{"normal_stiffness", kn}, {"box", Vector{0, 0, 0, 1}}}), 2));
        e.push_back(effect("dirichlet", MapParams({{"box", Vector{0, 0, L, 0}}, {"components", Vector{1}}}), 2));
        e.push_back(effect("uniform_traction", MapParams({{"value", Vector{T, 0}}, {"box", Vector{L, 0, L, 1}}}), 2));
        physics::Problem pb(PETSC_COMM_WORLD, mesh::mesh_polygon({{0, 0}, {L, 0}, {L, 1}, {0, 1}}, 0.2),
                            std::move(e), hstest::degree(degree));
        std::unique_ptr<solver::NonlinearSolver> ns;
        Vec u = solve(pb, ns);
        const double err = max_nodal_error(pb, u, [&](const double* x, double* v) {
          v[0] = T / kn + (a - 1) * x[0];
          v[1] = (b - 1) * x[1];
        });
        INFO("T = " << T << ", u_x(0) = " << T / kn << ", max nodal error " << err);
        CHECK(err < 1e-9);
      }
}

TEST_CASE("Sliding supports: a column under its own weight and a block under a top load", "[supports]") {
  const double E = 500, nu = 0.3, W = 1, H = 2;
  const physics::Lame m = physics::Lame::from_young_poisson(E, nu);
  auto slide = [](Vector box, double component) {
    return effect("dirichlet", MapParams({{"box", std::move(box)}, {"components", Vector{component}}}), 2);
  };
  const mesh::MeshData rect = mesh::mesh_polygon({{0, 0}, {W, 0}, {W, H}, {0, H}}, 0.25);
  SECTION("column between sliding walls under gravity g: u_y = -g (H y - y^2 / 2) / (lambda + 2 mu)") {
    const double g = 10;
    std::vector<physics::EffectPtr> e;
    e.push_back(physics::make_linear_elastic(E, nu));
    e.push_back(slide({0, 0, W, 0}, 1));
    e.push_back(slide({0, 0, 0, H}, 0));
    e.push_back(slide({W, 0, W, H}, 0));
    e.push_back(effect("body_force", MapParams({{"value", Vector{0, -g}}}), 2));
    physics::Problem pb(PETSC_COMM_WORLD, rect, std::move(e), hstest::degree(2));
    std::unique_ptr<solver::NonlinearSolver> ns;
    const double err = max_nodal_error(pb, solve(pb, ns), [&](const double* x, double* v) {
      v[0] = 0;
      v[1] = -g * (H * x[1] - 0.5 * x[1] * x[1]) / (m.lambda + 2 * m.mu);
    });
    INFO("u_y(H) = " << -g * H * H / 2 / (m.lambda + 2 * m.mu) << ", max nodal error " << err);
    CHECK(err < 1e-10);
  }
  SECTION("block on a sliding base, symmetry on x = 0, top load q: uniaxial plane strain") {
    const double q = 15;
    std::vector<physics::EffectPtr> e;
    e.push_back(physics::make_linear_elastic(E, nu));
    e.push_back(slide({0, 0, W, 0}, 1));
    e.push_back(slide({0, 0, 0, H}, 0));
    e.push_back(effect("uniform_traction", MapParams({{"value", Vector{0, -q}}, {"box", Vector{0, H, W, H}}}), 2));
    physics::Problem pb(PETSC_COMM_WORLD, rect, std::move(e), hstest::degree(1));
    std::unique_ptr<solver::NonlinearSolver> ns;
    const double err = max_nodal_error(pb, solve(pb, ns), [&](const double* x, double* v) {
      v[0] = q * nu * (1 + nu) / E * x[0];
      v[1] = -q * (1 - nu * nu) / E * x[1];
    });
    INFO("max nodal error " << err);
    CHECK(err < 1e-10);
  }
}

TEST_CASE("Springs reject bad keys naming them; a spring alone is a support", "[supports][input]") {
  auto message = [](MapParams p) {
    try {
      physics::make_effect("spring", p, 2);
    } catch (const core::InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  CHECK_THAT(message(MapParams()), Catch::Contains("stiffness"));
  CHECK_THAT(message(MapParams({{"stiffness", 0.0}})), Catch::Contains("stiffness"));
  CHECK_THAT(message(MapParams({{"normal_stiffness", -1.0}})), Catch::Contains("normal_stiffness"));
  CHECK_THAT(message(MapParams({{"stiffness", 1.0}, {"tangential_stiffness", 1.0}})), Catch::Contains("not both"));
  CHECK_THAT(message(MapParams({{"stiffness", 1.0}, {"box", Vector{0, 0, 1}}})), Catch::Contains("box"));
  CHECK(message(MapParams({{"tangential_stiffness", 2.0}})) == "accepted");
  const physics::EffectPtr s = physics::make_effect("spring", MapParams({{"stiffness", 1.0}}), 2);
  CHECK(s->is_support());
  CHECK_FALSE(s->is_material());
}

TEST_CASE("A body held by springs alone: the rigid modes are gone, the springs carry the load", "[supports]") {
  // The disk on an isotropic spring bed over its whole boundary, no Dirichlet condition, under
  // the seed's Gaussian traction (total force alpha e_y): at equilibrium the spring forces sum
  // to -alpha e_y (the material's internal forces sum to zero).
  const double alpha = 5.0;
  auto make = [](bool spring) {
    std::vector<physics::EffectPtr> e;
    e.push_back(physics::make_neo_hookean(500, 0.45));
    if (spring) e.push_back(effect("spring", MapParams({{"stiffness", 20.0}}), 2));
    e.push_back(physics::make_gaussian_traction({-1.0, 0.0}, {0.0, 1.0}, 0.2));
    return std::make_unique<physics::Problem>(PETSC_COMM_WORLD, hstest::disk_mesh(0.1), std::move(e),
                                              hstest::degree(1));
  };
  auto with = make(true), without = make(false);
  std::unique_ptr<solver::NonlinearSolver> ns;
  solver::SolverOptions so;
  so.rtol = 1e-12;
  ns = std::make_unique<solver::NonlinearSolver>(*with, so);
  REQUIRE(ns->solve(alpha).converged);
  // Spring force = residual(with) - residual(without) at the solution (load factor 0).
  core::VecH r1 = with->create_vector(), r0 = with->create_vector(), ones = with->create_vector();
  REQUIRE(with->residual(ns->solution(), 0.0, r1));
  REQUIRE(without->residual(ns->solution(), 0.0, r0));
  HS_PETSC(VecAXPY(r1, -1.0, r0));
  double total[2];
  for (int k = 0; k < 2; ++k) {
    hstest::interpolate(*with, [k](const double*, double* v) { v[0] = k == 0, v[1] = k == 1; }, ones);
    PetscScalar s;
    HS_PETSC(VecDot(r1, ones, &s));
    total[k] = PetscRealPart(s);
  }
  INFO("spring force on the body " << -total[0] << ", " << -total[1]);
  CHECK(std::abs(total[0]) < 1e-8 * alpha);
  CHECK(total[1] == Approx(alpha).epsilon(1e-8));  // r_s = K u is the force the body exerts
}
