/// Hand-written element loops against PETSc's generic pointwise assembly (same quadrature, same
/// kernel: they must agree to round-off), and the residual as the gradient of the energy.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>
#include <string>
#include <utility>

#include "hypershape/physics/hyperelastic.hpp"

#include "support/helpers.hpp"

using namespace hypershape;
using hstest::on_plane;

namespace {

struct Case {
  const char* name;
  int dim;
  int degree;
};

/// A small problem: the clamped disk with a Gaussian traction in 2D, a cube clamped on x = 0
/// with a Gaussian traction near the opposite corner in 3D; the Neo-Hookean pointwise or on the
/// cells' mean dilatation.
std::unique_ptr<physics::Problem> make_problem(int dim, int degree, bool mean_dilatation = false) {
  std::vector<physics::EffectPtr> effects;
  effects.push_back(mean_dilatation ? physics::make_neo_hookean_mean_dilatation(500.0, 0.3)
                                    : physics::make_neo_hookean(500.0, 0.3));
  mesh::MeshData m;
  if (dim == 2) {
    m = hstest::disk_mesh(0.2);
    effects.push_back(physics::make_dirichlet_patch({1.0, 0.0}, 0.5));
    effects.push_back(physics::make_gaussian_traction({-1.0, 0.0}, {0.0, 1.0}, 0.2));
  } else {
    m = mesh::mesh_box(3, 1.0, degree == 1 ? 0.3 : 0.4);
    effects.push_back(physics::make_dirichlet("clamp", on_plane(0, 0.0)));
    effects.push_back(physics::make_gaussian_traction({1.0, 1.0, 1.0}, {0.0, 0.0, -1.0}, 0.3));
  }
  return std::make_unique<physics::Problem>(PETSC_COMM_WORLD, m, std::move(effects),
                                            hstest::degree(degree));
}

/// A smooth, clearly non-linear displacement with gradients of order 0.1-0.3 that vanishes on
/// the clamped boundary (so that zeroing the constrained dofs leaves it intact).
void smooth_field(const double* x, double* u, int dim, double scale) {
  // 2D: zero on the patch |x - (1, 0)| <= 0.5; 3D: zero on x = 0.
  const double d2 = (x[0] - 1.0) * (x[0] - 1.0) + x[1] * x[1];
  const double phi = dim == 2 ? std::max(0.0, d2 - 0.25) / 3.0 : x[0];
  u[0] = scale * phi * (0.4 * std::sin(1.3 * x[0] + 0.4 * x[1]) + 0.15 * x[1] * x[1]);
  u[1] = scale * phi * (0.3 * std::cos(0.9 * x[0] - 1.1 * x[1]) - 0.2 * x[0] * x[1]);
  if (dim == 3) {
    u[0] += scale * phi * 0.15 * x[2];
    u[1] += scale * phi * 0.1 * std::sin(2.0 * x[2]);
    u[2] = scale * phi * (0.3 * std::sin(x[0] + x[1] + x[2]) - 0.2 * x[2] * x[2]);
  }
}

const Case cases[] = {{"2D P1", 2, 1}, {"2D P2", 2, 2}, {"3D P1", 3, 1}, {"3D P2", 3, 2}};

/// J (assembled at u by the hand-written loops) equals PETSc's pointwise assembly to round-off.
void check_equals_pointwise(const physics::Problem& p, Vec u, Mat J) {
  core::MatH J_pw = p.create_matrix();
  p.jacobian_pointwise(u, J_pw);
  PetscReal jn, dn;
  HS_PETSC(MatNorm(J, NORM_FROBENIUS, &jn));
  HS_PETSC(MatAXPY(J_pw, -1.0, J, DIFFERENT_NONZERO_PATTERN));
  HS_PETSC(MatNorm(J_pw, NORM_FROBENIUS, &dn));
  INFO("tangent: ||J||_F = " << jn << ", relative difference " << dn / jn);
  REQUIRE(jn > 0);
  CHECK(dn / jn < 1e-12);
}

/// Two deformed states of p: the smooth field at half and at full amplitude.
std::pair<core::VecH, core::VecH> two_states(const physics::Problem& p, int dim) {
  std::pair<core::VecH, core::VecH> out{p.create_vector(), p.create_vector()};
  hstest::interpolate(
      p, [dim](const double* x, double* v) { smooth_field(x, v, dim, 0.5); }, out.first);
  hstest::interpolate(
      p, [dim](const double* x, double* v) { smooth_field(x, v, dim, 1.0); }, out.second);
  return out;
}

}  // namespace

TEST_CASE("Hand-written residual and tangent equal PETSc's pointwise assembly", "[assembly]") {
  for (const Case& c : cases) {
    DYNAMIC_SECTION(c.name) {
      auto p = make_problem(c.dim, c.degree);
      const int dim = c.dim;
      core::VecH u = p->create_vector(), r = p->create_vector(), r_pw = p->create_vector();
      hstest::interpolate(
          *p, [dim](const double* x, double* v) { smooth_field(x, v, dim, 1.0); }, u);
      const double jmin = p->min_det_f(u);
      INFO("min det F = " << jmin);
      REQUIRE(jmin > 0.3);
      REQUIRE(jmin < 0.97);  // the state is really deformed

      REQUIRE(p->residual(u, 0.0, r));
      p->residual_pointwise(u, r_pw);
      PetscReal rn;
      HS_PETSC(VecNorm(r, NORM_2, &rn));
      REQUIRE(rn > 1.0);  // E = 500 and strains ~0.1: far from zero
      const double dr = hstest::rel_diff(r_pw, r);
      INFO("residual: ||r|| = " << rn << ", relative difference " << dr);
      CHECK(dr < 1e-12);

      core::MatH J = p->create_matrix();
      REQUIRE(p->jacobian(u, J));
      check_equals_pointwise(*p, u, J);
    }
  }
}

TEST_CASE("The tangent's matrix from the cells is DMCreateMatrix's: type, sizes, block size, pattern",
          "[assembly]") {
  for (const Case& c : cases) {
    DYNAMIC_SECTION(c.name) {
      auto p = make_problem(c.dim, c.degree);
      core::MatH A = p->create_matrix(), B;
      HS_PETSC(DMCreateMatrix(p->dm(), B.out()));
      MatType ta, tb;
      HS_PETSC(MatGetType(A, &ta));
      HS_PETSC(MatGetType(B, &tb));
      CHECK(std::string(ta) == std::string(tb));
      PetscInt ma, na, mb, nb, bsa, bsb;
      HS_PETSC(MatGetSize(A, &ma, &na));
      HS_PETSC(MatGetSize(B, &mb, &nb));
      HS_PETSC(MatGetBlockSize(A, &bsa));
      HS_PETSC(MatGetBlockSize(B, &bsb));
      CHECK(ma == mb);
      CHECK(na == nb);
      CHECK(bsa == bsb);
      if (core::size(PETSC_COMM_WORLD) > 1) continue;  // there it is DMCreateMatrix's own
      DM dm;
      HS_PETSC(MatGetDM(A, &dm));
      CHECK(dm == p->dm());
      PetscInt n, m;
      const PetscInt *ia, *ja, *ib, *jb;
      PetscBool da, db;
      HS_PETSC(MatGetRowIJ(A, 0, PETSC_FALSE, PETSC_FALSE, &n, &ia, &ja, &da));
      HS_PETSC(MatGetRowIJ(B, 0, PETSC_FALSE, PETSC_FALSE, &m, &ib, &jb, &db));
      REQUIRE((da && db && n == m));
      REQUIRE(n > 0);
      CHECK(std::equal(ia, ia + n + 1, ib));
      CHECK(std::equal(ja, ja + ia[n], jb));
      HS_PETSC(MatRestoreRowIJ(A, 0, PETSC_FALSE, PETSC_FALSE, &n, &ia, &ja, &da));
      HS_PETSC(MatRestoreRowIJ(B, 0, PETSC_FALSE, PETSC_FALSE, &m, &ib, &jb, &db));
      PetscReal norm;
      HS_PETSC(MatNorm(A, NORM_FROBENIUS, &norm));
      CHECK(norm == 0.0);
    }
  }
}

TEST_CASE("Re-assembly straight into the CSR values equals PETSc's assembly", "[assembly]") {
  int ranks;
  MPI_Comm_size(PETSC_COMM_WORLD, &ranks);
  for (const Case& c : cases) {
    DYNAMIC_SECTION(c.name) {
      auto p = make_problem(c.dim, c.degree);
      auto [u0, u] = two_states(*p, c.dim);
      core::MatH J = p->create_matrix();
      REQUIRE(p->jacobian(u0, J));  // fixes the pattern
      {
        const physics::CellMatrixAdder adder(p->space(), J);
        CHECK(adder.direct() == (ranks == 1));  // one rank: SeqAIJ, the direct path
      }
      REQUIRE(p->jacobian(u, J));  // the second assembly: into the values of the first
      check_equals_pointwise(*p, u, J);
    }
  }
}

TEST_CASE("Re-assembly straight into the CSR values is MatSetValues' sum to the bit, on every matrix of the pattern",
          "[assembly]") {
  // The direct path adds each cell's entries in pairs (a node's two dofs), with offsets kept per
  // pattern and the matrices known to have it: the same IEEE additions in the same cell order as
  // MatSetValues into another matrix type (here BAIJ, which has no direct path).
  int ranks;
  MPI_Comm_size(PETSC_COMM_WORLD, &ranks);
  if (ranks != 1) return;  // the direct path is serial
  for (const Case& c : cases) {
    DYNAMIC_SECTION(c.name) {
      auto p = make_problem(c.dim, c.degree);
      auto [u0, u] = two_states(*p, c.dim);
      core::MatH J1 = p->create_matrix(), J2 = p->create_matrix(), ref;
      HS_PETSC(MatConvert(J1, MATSEQBAIJ, MAT_INITIAL_MATRIX, ref.out()));
      REQUIRE(p->jacobian(u, ref));  // MatSetValues
      const auto same_as_ref = [&](Mat J) {
        core::MatH d;
        HS_PETSC(MatConvert(ref, MATSEQAIJ, MAT_INITIAL_MATRIX, d.out()));
        PetscReal jn, dn;
        HS_PETSC(MatNorm(J, NORM_FROBENIUS, &jn));
        HS_PETSC(MatAXPY(d, -1.0, J, DIFFERENT_NONZERO_PATTERN));
        HS_PETSC(MatNorm(d, NORM_FROBENIUS, &dn));
        REQUIRE(jn > 0);
        return dn == 0.0;
      };
      for (int k = 0; k < 2; ++k) {  // the second time through, both matrices' patterns are known
        REQUIRE(p->jacobian(u0, J1));
        REQUIRE(p->jacobian(u, J1));
        CHECK(physics::CellMatrixAdder(p->space(), J1).direct());
        CHECK(same_as_ref(J1));
        REQUIRE(p->jacobian(u, J2));
        CHECK(same_as_ref(J2));
      }
    }
  }
}

TEST_CASE("Energy and residual in one pass equal the two passes bit for bit", "[assembly]") {
  // A line search's trial takes both from Problem::energy_residual, and the next line search
  // starts from its stored energy and internal force; the solver's data must not depend on it. Both materials (pointwise and mean dilatation), every element.
  for (const Case& c : cases)
    for (const bool mean : {false, true}) {
      DYNAMIC_SECTION(c.name << (mean ? ", mean dilatation" : "")) {
        auto p = make_problem(c.dim, c.degree, mean);
        const int dim = c.dim;
        core::VecH u = p->create_vector(), r = p->create_vector(), r1 = p->create_vector();
        hstest::interpolate(
            *p, [dim](const double* x, double* v) { smooth_field(x, v, dim, 1.0); }, u);
        const double s = 3.7;
        double e = 0, e1 = 0, internal = 0;
        REQUIRE(p->energy(u, s, e));
        REQUIRE(p->residual(u, s, r));
        core::VecH force = p->create_vector();
        REQUIRE(p->energy_residual(u, s, e1, r1, &internal, force));
        REQUIRE(std::isfinite(e));
        CHECK(e1 == e);
        PetscBool same = PETSC_FALSE;
        HS_PETSC(VecEqual(r, r1, &same));
        CHECK(same);
        // The stored part and the loads' work give the same energy at any load factor.
        double e2;
        REQUIRE(p->energy(u, -1.25, e2));
        CHECK(p->energy_from_internal(u, -1.25, internal) == e2);
        CHECK(e2 != e);
        // Likewise the stored energy's gradient and the residual at any load factor.
        core::VecH r2 = p->create_vector(), r3 = p->create_vector();
        REQUIRE(p->residual(u, -1.25, r2));
        p->residual_from_internal(force, -1.25, r3);
        HS_PETSC(VecEqual(r2, r3, &same));
        CHECK(same);
        // Inadmissible (inverted) states: false, the residual left as it was.
        HS_PETSC(VecScale(u, 40.0));
        REQUIRE_FALSE(p->energy(u, s, e));
        HS_PETSC(VecCopy(r, r1));
        CHECK_FALSE(p->energy_residual(u, s, e1, r1));
        CHECK(std::isinf(e1));
        HS_PETSC(VecEqual(r, r1, &same));
        CHECK(same);
      }
    }
}

TEST_CASE("The residual is the gradient of the potential energy", "[assembly]") {
  for (const Case& c : cases) {
    DYNAMIC_SECTION(c.name) {
      auto p = make_problem(c.dim, c.degree);
      const int dim = c.dim;
      REQUIRE(p->load_norm() > 0);
      core::VecH u = p->create_vector(), v = p->create_vector(), r = p->create_vector(),
                 w = p->create_vector();
      hstest::interpolate(
          *p, [dim](const double* x, double* y) { smooth_field(x, y, dim, 1.0); }, u);
      // A direction unrelated to u.
      hstest::interpolate(
          *p,
          [dim](const double* x, double* y) {
            y[0] = std::cos(2.0 * x[1]) + 0.3 * x[0];
            y[1] = std::sin(1.7 * x[0]) - 0.2;
            if (dim == 3) y[2] = x[0] * x[1] - 0.5 * std::cos(x[2]);
          },
          v);
      for (double s : {0.0, 0.7}) {
        REQUIRE(p->residual(u, s, r));
        PetscScalar slope;
        HS_PETSC(VecDot(r, v, &slope));
        const double eps = 1e-4;
        auto energy_at = [&](double t) {
          HS_PETSC(VecWAXPY(w, t, v, u));
          double e = 0;
          REQUIRE(p->energy(w, s, e));
          return e;
        };
        // 4th-order central difference of t -> Pi(u + t v) at t = 0.
        const double fd =
            (-energy_at(2 * eps) + 8 * energy_at(eps) - 8 * energy_at(-eps) + energy_at(-2 * eps)) /
            (12 * eps);
        INFO("load factor " << s << ": r.v = " << slope << ", FD = " << fd);
        REQUIRE(std::abs(slope) > 1e-3);
        CHECK(std::abs(fd - slope) <= 1e-7 * std::abs(slope));
      }
    }
  }
}

TEST_CASE("Energy, residual and tangent report det F <= 0 instead of returning garbage",
          "[assembly]") {
  auto p = make_problem(2, 1);
  core::VecH u = p->create_vector(), r = p->create_vector();
  // Folds the disk over itself: u_x = -2.5 x gives F_11 = -1.5 everywhere.
  hstest::interpolate(
      *p,
      [](const double* x, double* v) {
        v[0] = -2.5 * x[0];
        v[1] = 0.0;
      },
      u);
  REQUIRE(p->min_det_f(u) < 0);
  double e = 0;
  CHECK_FALSE(p->energy(u, 0.0, e));
  CHECK(std::isinf(e));
  CHECK_FALSE(p->residual(u, 0.0, r));
  core::MatH J = p->create_matrix();
  CHECK_FALSE(p->jacobian(u, J));
}

TEST_CASE("The 2D tangent's point contribution is Eigen's product, bit for bit", "[assembly]") {
  // add_point_tangent (2D: along AG's rows, vectorised) must give the numbers of the Eigen
  // expression it replaced, Ke(a i, :) += w G(a, :) AG(i:, :): the factory's data rest on it.
  constexpr int NB = 6, D = 2, ND = NB * D;
  Eigen::Matrix<double, NB, D> G;
  Eigen::Matrix<double, D * D, ND, Eigen::RowMajor> AG;
  std::uint64_t state = 12345;
  auto next = [&] {  // deterministic values with full mantissas
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return double(state >> 11) / double(1ULL << 53) * 2.0 - 1.0;
  };
  for (int a = 0; a < NB; ++a)
    for (int j = 0; j < D; ++j) G(a, j) = next();
  for (int r = 0; r < D * D; ++r)
    for (int c = 0; c < ND; ++c) AG(r, c) = next();
  const Eigen::Matrix<double, D * D, ND> AGc = AG;  // the former, column-major layout
  Eigen::Matrix<double, ND, ND, Eigen::RowMajor> mine, eigen;
  for (int r = 0; r < ND; ++r)
    for (int c = 0; c < ND; ++c) mine(r, c) = eigen(r, c) = next();
  for (const double w : {0.37, 1.0, 2.5e-3}) {
    physics::detail::add_point_tangent<D, NB>(G, AG, w, mine);
    for (int a = 0; a < NB; ++a)
      for (int i = 0; i < D; ++i) eigen.row(a * D + i).noalias() += w * (G.row(a) * AGc.middleRows<D>(i * D));
  }
  CHECK(std::memcmp(mine.data(), eigen.data(), sizeof(double) * ND * ND) == 0);
}

namespace {

/// The 2D element loops' hand-written sums against the Eigen products they replaced (hyperelastic.hpp):
/// every bit the same on random arguments, so the datasets keep theirs.
template <int NB>
void check_kernel_sums() {
  std::mt19937_64 gen(20261129 + NB);
  std::normal_distribution<double> normal;
  auto fill = [&](auto& m, double scale) {
    for (Eigen::Index k = 0; k < m.size(); ++k) m.data()[k] = scale * normal(gen);
  };
  auto same = [](const auto& a, const auto& b) { return std::memcmp(a.data(), b.data(), sizeof(double) * std::size_t(a.size())) == 0; };
  int differ_f = 0, differ_r = 0, differ_ag = 0;
  for (int t = 0; t < 20000; ++t) {
    Eigen::Matrix<double, NB, 2> ue, G, re;
    physics::Tensor<2> P;
    physics::Tangent<2> A;
    fill(ue, 0.1);
    fill(G, 10.0);
    fill(re, 1.0);
    fill(P, 1.0);
    fill(A, 1.0);
    const double w = std::abs(normal(gen)) * 1e-3;
    const physics::Tensor<2> F = physics::Tensor<2>::Identity() + ue.transpose() * G;
    differ_f += !same(F, physics::detail::deformation_gradient<2, NB>(ue, G));
    Eigen::Matrix<double, NB, 2> re_eigen = re;
    re_eigen.noalias() += w * (G * P.transpose());
    physics::detail::add_point_residual<2, NB>(G, P, w, re);
    differ_r += !same(re, re_eigen);
    Eigen::Matrix<double, 4, 2 * NB, Eigen::RowMajor> AG, AG_eigen;
    for (int b = 0; b < NB; ++b)
      for (int k = 0; k < 2; ++k) AG_eigen.col(b * 2 + k).noalias() = A.template middleCols<2>(k * 2) * G.row(b).transpose();
    physics::detail::tangent_gradients<2, NB>(A, G, AG);
    differ_ag += !same(AG, AG_eigen);
  }
  CHECK(differ_f == 0);
  CHECK(differ_r == 0);
  CHECK(differ_ag == 0);
}

}  // namespace

TEST_CASE("2D element loops sum as Eigen's products did, bit for bit", "[physics][assembly]") {
  SECTION("P1") { check_kernel_sums<3>(); }
  SECTION("P2") { check_kernel_sums<6>(); }
}
