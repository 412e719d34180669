/// The follower pressure (`pressure` with `follower: true`, t = -p J F^-T N): its tangent against
/// central differences of the residual (2D and 3D, P1 and P2, at a load factor), its load at rest
/// equal to the dead pressure's, frame indifference (a rigid rotation Q of the body turns every
/// nodal force by Q, where a dead load would stay), a non-symmetric load stiffness on part of a
/// free boundary, and the displacement-controlled path with LU solves reaching a state whose true
/// residual is within rtol and whose tangent's symmetric part is positive definite.
#include <catch2/catch.hpp>
#include <array>
#include <cmath>
#include <random>

#include "hypershape/core/error.hpp"
#include "hypershape/core/vec_array.hpp"
#include "hypershape/physics/registry.hpp"
#include "hypershape/physics/tensor.hpp"
#include "hypershape/solver/nonlinear.hpp"
#include "support/helpers.hpp"

using namespace hypershape;
using core::MapParams;
using Vector = std::vector<double>;

namespace {

/// The unit square (cube) clamped on its face y = 0 (z = 0), a pressure p on the opposite face.
std::unique_ptr<physics::Problem> block(int dim, int degree, bool follower, double p) {
  std::vector<physics::EffectPtr> e;
  e.push_back(physics::make_neo_hookean(100, 0.3));
  const Vector bottom = dim == 2 ? Vector{0, 0, 1, 0} : Vector{0, 0, 0, 1, 1, 0};
  const Vector top = dim == 2 ? Vector{0, 1, 1, 1} : Vector{0, 0, 1, 1, 1, 1};
  e.push_back(physics::make_effect("dirichlet", MapParams({{"box", bottom}}), dim));
  e.push_back(physics::make_effect(
      "pressure", MapParams({{"value", p}, {"box", top}, {"follower", std::string(follower ? "true" : "false")}}), dim));
  return std::make_unique<physics::Problem>(PETSC_COMM_WORLD, mesh::mesh_box(dim, 1.0, dim == 2 ? 0.2 : 0.4),
                                            std::move(e), hstest::degree(degree));
}

void random_vector(Vec v, unsigned seed, double scale) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> d(-scale, scale);
  PetscInt n;
  HS_PETSC(VecGetLocalSize(v, &n));
  core::VecArray<PetscScalar> a(v);
  for (PetscInt i = 0; i < n; ++i) a[i] = d(rng);
}

}  // namespace

TEST_CASE("Follower pressure: the tangent is the residual's derivative, and not symmetric", "[follower]") {
  for (int dim : {2, 3})
    for (int degree : {1, 2}) {
      DYNAMIC_SECTION(dim << "D P" << degree) {
        auto pb = block(dim, degree, true, 5.0);
        REQUIRE_FALSE(pb->conservative());
        core::VecH u = pb->create_vector(), v = pb->create_vector(), Kv = pb->create_vector(),
                   rp = pb->create_vector(), rm = pb->create_vector(), w = pb->create_vector();
        random_vector(u, 1, 0.01);
        random_vector(v, 2, 1.0);
        const double s = 2.3;  // the load factor scales the load stiffness too
        core::MatH J = pb->create_matrix();
        REQUIRE(pb->jacobian(u, J, s));
        HS_PETSC(MatMult(J, v, Kv));
        const double h = 1e-6;
        HS_PETSC(VecWAXPY(w, h, v, u));
        REQUIRE(pb->residual(w, s, rp));
        HS_PETSC(VecWAXPY(w, -h, v, u));
        REQUIRE(pb->residual(w, s, rm));
        HS_PETSC(VecAXPY(rp, -1.0, rm));
        HS_PETSC(VecScale(rp, 1.0 / (2 * h)));
        const double fd = hstest::rel_diff(rp, Kv);
        // Without the follower's stiffness the tangent would miss by this much.
        auto dead = block(dim, degree, false, 5.0);
        core::MatH J0 = dead->create_matrix();
        REQUIRE(dead->jacobian(u, J0));
        HS_PETSC(MatMult(J0, v, w));
        const double miss = hstest::rel_diff(rp, w);
        const double asym = hstest::asymmetry(J);
        INFO("|J v - FD| / |J v| = " << fd << " (dead tangent: " << miss << "), |K - K^T| / |K| = " << asym);
        CHECK(fd < 1e-7);
        CHECK(miss > 1e3 * fd);
        CHECK(asym > 1e-4);
        CHECK(hstest::asymmetry(J0) < 1e-14);
      }
    }
}

TEST_CASE("Follower pressure: the dead load at rest, turned with the body by a rigid rotation", "[follower]") {
  for (int dim : {2, 3})
    for (int degree : {1, 2}) {
      DYNAMIC_SECTION(dim << "D P" << degree) {
        auto follower = block(dim, degree, true, 3.0), dead = block(dim, degree, false, 3.0);
        core::VecH u = follower->create_vector();
        // At rest the two loads are the same vector.
        const core::VecH f0 = follower->create_vector(), fd = follower->create_vector();
        HS_PETSC(VecCopy(follower->load_at(u), f0));
        HS_PETSC(VecCopy(dead->load(), fd));
        CHECK(hstest::rel_diff(f0, fd) < 1e-14);
        CHECK(hstest::rel_diff(follower->load(), fd) < 1e-14);
        // u = (Q - I) X, Q a rotation by 0.3 about the z axis: exact in P1 and P2. (The clamped
        // face keeps u = 0, but the loaded face has no node on it.)
        const double c = std::cos(0.3), sn = std::sin(0.3);
        hstest::interpolate(*follower, [&](const double* x, double* v) {
          v[0] = (c - 1) * x[0] - sn * x[1];
          v[1] = sn * x[0] + (c - 1) * x[1];
        }, u);
        const Vec f = follower->load_at(u);
        double err = 0, scale = 0;
        {
          core::VecArray<const PetscScalar> a(f), b(f0);
          PetscInt n;
          HS_PETSC(VecGetLocalSize(f, &n));
          for (PetscInt i = 0; i + dim <= n; i += dim) {  // whole nodes: no node is half-constrained
            const double qx = c * b[i] - sn * b[i + 1], qy = sn * b[i] + c * b[i + 1];
            err = std::max({err, std::abs(a[i] - qx), std::abs(a[i + 1] - qy), dim == 3 ? std::abs(a[i + 2] - b[i + 2]) : 0.0});
            scale = std::max(scale, std::abs(b[i]) + std::abs(b[i + 1]) + (dim == 3 ? std::abs(b[i + 2]) : 0.0));
          }
        }
        MPI_Allreduce(MPI_IN_PLACE, &err, 1, MPI_DOUBLE, MPI_MAX, PETSC_COMM_WORLD);
        MPI_Allreduce(MPI_IN_PLACE, &scale, 1, MPI_DOUBLE, MPI_MAX, PETSC_COMM_WORLD);
        INFO("max |f(u) - Q f(0)| / max |f(0)| = " << err / scale);
        CHECK(scale > 0);
        CHECK(err < 1e-12 * scale);
      }
    }
}

TEST_CASE("Follower pressure on part of a boundary: the path with LU solves converges", "[follower]") {
  // The seed's disk, clamped near (1, 0), pushed by a pressure on the boundary within 0.8 of
  // (-1, 0): a free boundary piece, so the load is not conservative.
  std::vector<physics::EffectPtr> e;
  e.push_back(physics::make_neo_hookean(500, 0.4));
  e.push_back(physics::make_dirichlet_patch({1.0, 0.0}, 0.5));
  e.push_back(physics::make_follower_pressure(1.0, physics::Region::ball({-1.0, 0.0}, 0.8), 2));
  auto pb = std::make_unique<physics::Problem>(PETSC_COMM_WORLD, hstest::disk_mesh(0.1), std::move(e), hstest::degree(1));
  solver::NonlinearSolver ns(*pb);
  const solver::TargetResult t = ns.solve_for_target(0.1);
  INFO(t.reason << ": alpha " << t.alpha << ", " << t.newton_iterations << " Newton its, "
                << t.linear.numeric_factorizations << " factorisations");
  REQUIRE(t.converged);
  CHECK(t.negative_pivots == 0);  // (K + K^T)/2 positive definite
  CHECK(std::abs(t.max_displacement / 0.1 - 1) <= 1e-3);
  // The true residual, from scratch, within rtol of the load.
  core::VecH r = pb->create_vector();
  REQUIRE(pb->residual(ns.solution(), t.alpha, r));
  PetscReal rn;
  HS_PETSC(VecNorm(r, NORM_2, &rn));
  CHECK(rn <= 1e-12 + 1e-9 * t.alpha * pb->load_norm());
  // Load control at that alpha from rest reaches the same state.
  solver::NonlinearSolver lc(*pb);
  REQUIRE(lc.solve(t.alpha).converged);
  CHECK(hstest::rel_diff(lc.solution(), ns.solution()) < 1e-7);
}

TEST_CASE("Follower pressure: the stability check counts the negative eigenvalues of (K + K^T)/2", "[follower]") {
  // K from the LU path, shifted between the 3rd and 4th eigenvalues of its symmetric part: the
  // LDL^T inertia of (K + K^T)/2 must say 3, as dense eigenvalues do; the LU factor itself solves.
  auto pb = block(2, 1, true, 5.0);
  core::VecH u = pb->create_vector(), b = pb->create_vector(), x = pb->create_vector(), r = pb->create_vector();
  random_vector(u, 3, 0.01);
  solver::Tangent tangent(*pb, {}, "");
  REQUIRE(tangent.lu());
  REQUIRE(tangent.assemble(u, 2.0));
  Mat K = tangent.matrix();
  REQUIRE(hstest::asymmetry(K) > 1e-4);
  Mat S;
  HS_PETSC(MatTranspose(K, MAT_INITIAL_MATRIX, &S));
  HS_PETSC(MatAXPY(S, 1.0, K, DIFFERENT_NONZERO_PATTERN));
  HS_PETSC(MatScale(S, 0.5));
  const std::vector<PetscScalar> ev = hstest::dense_eigenvalues(S);
  HS_PETSC(MatDestroy(&S));
  REQUIRE(ev.size() > 4);
  REQUIRE(ev[0] > 0);
  tangent.shift(-0.5 * (ev[2] + ev[3]));
  REQUIRE(tangent.factorise());
  CHECK(tangent.negative_eigenvalues() == 3);
  // The LU factor solves the non-symmetric system.
  random_vector(b, 4, 1.0);
  REQUIRE(tangent.solve(b, x, false));
  HS_PETSC(MatMult(tangent.matrix(), x, r));
  CHECK(hstest::rel_diff(r, b) < 1e-10);
}

TEST_CASE("Follower pressure on a cube on rollers: the homogeneous closed form, dead and follower", "[follower]") {
  // The unit cube on rollers (u_i = 0 on x_i = 0), pressure p on z = 1: F = diag(a, a, c) with
  // P_1(a, a, c) = 0 and P_3 = -p (dead) or -p a^2 (follower: the Cauchy stress is -p on the
  // deformed face, whose area per reference area is a^2). Neo-Hookean principal stresses
  // P_i = mu (l_i - 1/l_i) + lambda ln J / l_i, solved here by Newton; P1 is exact for it.
  const double E = 100, nu = 0.3, p = 15;
  const physics::Lame l = physics::Lame::from_young_poisson(E, nu);
  auto principal = [&](double li, double J) { return l.mu * (li - 1 / li) + l.lambda * std::log(J) / li; };
  auto closed_form = [&](bool follower) {
    double a = 1, c = 1;
    for (int it = 0; it < 50; ++it) {
      auto g = [&](double x, double z) {
        return std::array<double, 2>{principal(x, x * x * z), principal(z, x * x * z) + p * (follower ? x * x : 1.0)};
      };
      const auto g0 = g(a, c), ga = g(a + 1e-7, c), gc = g(a, c + 1e-7);
      const double j11 = (ga[0] - g0[0]) / 1e-7, j12 = (gc[0] - g0[0]) / 1e-7, j21 = (ga[1] - g0[1]) / 1e-7,
                   j22 = (gc[1] - g0[1]) / 1e-7, det = j11 * j22 - j12 * j21;
      a -= (j22 * g0[0] - j12 * g0[1]) / det;
      c -= (-j21 * g0[0] + j11 * g0[1]) / det;
    }
    return std::array<double, 2>{a, c};
  };
  std::array<double, 2> stretch[2];
  for (bool follower : {false, true}) {
    std::vector<physics::EffectPtr> e;
    e.push_back(physics::make_neo_hookean(E, nu));
    for (int i = 0; i < 3; ++i) {
      Vector box{0, 0, 0, 1, 1, 1};
      box[std::size_t(3 + i)] = 0;
      e.push_back(physics::make_effect("dirichlet", MapParams({{"box", box}, {"components", Vector{double(i)}}}), 3));
    }
    e.push_back(follower ? physics::make_follower_pressure(p, physics::Region::box({0, 0, 1}, {1, 1, 1}), 3)
                         : physics::make_pressure(p, physics::Region::box({0, 0, 1}, {1, 1, 1}), 3));
    physics::Problem pb(PETSC_COMM_WORLD, mesh::mesh_box(3, 1.0, 0.5), std::move(e), hstest::degree(1));
    solver::SolverOptions so;
    so.rtol = 1e-12;
    solver::NonlinearSolver ns(pb, so);
    REQUIRE(ns.solve(1.0).converged);
    const auto s = stretch[follower] = closed_form(follower);
    const physics::NodalField f = pb.gather(ns.solution());
    const auto& X = pb.space().canonical_coords();
    double err = 0;
    for (std::size_t k = 0; 3 * k < f.values.size(); ++k)
      for (int i = 0; i < 3; ++i)
        err = std::max(err, std::abs(f.values[3 * k + i] - ((i < 2 ? s[0] : s[1]) - 1) * X[3 * k + i]));
    MPI_Bcast(&err, 1, MPI_DOUBLE, 0, PETSC_COMM_WORLD);
    INFO((follower ? "follower" : "dead") << ": a = " << s[0] << ", c = " << s[1] << ", max nodal error " << err);
    CHECK(err < 1e-9);
  }
  INFO("c dead " << stretch[0][1] << ", follower " << stretch[1][1]);
  CHECK(stretch[1][1] < stretch[0][1] - 0.01);  // the face widens: the follower pushes harder
}
