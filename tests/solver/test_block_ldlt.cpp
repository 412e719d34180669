/// BlockLdlt2, the blocked LDL^T's own factorisation: the same bits as PETSc's U^T D U for 2x2
/// blocks (the factory's data must not change with it), the same inertia, the same failure on a
/// zero pivot.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "hypershape/solver/block_ldlt.hpp"
#include "hypershape/solver/ldlt.hpp"
#include "support/helpers.hpp"

using namespace hypershape;

namespace {

/// PETSc's own Cholesky of an SBAIJ matrix of 2x2 blocks in its natural ordering.
core::KSPH petsc_factor(Mat S) {
  core::KSPH ksp;
  HS_PETSC(KSPCreate(PETSC_COMM_SELF, ksp.out()));
  solver::configure_direct_solver(ksp, PETSC_COMM_SELF, 2);  // PETSc's own LDL^T (2D, one rank)
  PC pc;
  HS_PETSC(KSPGetPC(ksp, &pc));
  HS_PETSC(PCFactorSetMatOrderingType(pc, MATORDERINGNATURAL));
  HS_PETSC(KSPSetOperators(ksp, S, S));
  HS_PETSC(PCSetUp(pc));
  return ksp;
}

/// BlockLdlt2 of the same matrix (its pattern and values as SBAIJ stores them).
bool own_factor(Mat S, solver::BlockLdlt2& f) {
  const PetscInt *ia, *ja;
  PetscInt nb;
  PetscBool done;
  HS_PETSC(MatGetRowIJ(S, 0, PETSC_FALSE, PETSC_TRUE, &nb, &ia, &ja, &done));
  REQUIRE(done);
  f.analyse(nb, ia, ja);
  HS_PETSC(MatRestoreRowIJ(S, 0, PETSC_FALSE, PETSC_TRUE, &nb, &ia, &ja, &done));
  PetscScalar* v;
  HS_PETSC(MatSeqSBAIJGetArray(S, &v));
  const bool ok = f.factorise(v);
  HS_PETSC(MatSeqSBAIJRestoreArray(S, &v));
  return ok;
}

std::vector<double> values(Vec v) {
  const PetscScalar* a;
  PetscInt n;
  HS_PETSC(VecGetLocalSize(v, &n));
  HS_PETSC(VecGetArrayRead(v, &a));
  std::vector<double> out(a, a + n);
  HS_PETSC(VecRestoreArrayRead(v, &a));
  return out;
}

}  // namespace

TEST_CASE("BlockLdlt2 factorises and solves as PETSc's blocked LDL^T does, to the bit", "[solver]") {
  // K - sigma I of a P1 and a P2 tangent at a deformed state, definite and indefinite; solves of
  // the load and of a vector with every entry nonzero. A different order of any sum would show.
  for (const int degree : {1, 2}) {
    physics::Problem p{PETSC_COMM_WORLD, hstest::disk_mesh(0.2), hstest::disk_effects(), hstest::degree(degree)};
    core::VecH u = p.create_vector(), b = p.create_vector(), x = p.create_vector();
    HS_PETSC(VecCopy(p.load(), u));
    HS_PETSC(VecScale(u, 0.02));  // a state whose tangent is not the linear one
    core::MatH K = p.create_matrix();
    REQUIRE(p.jacobian(u, K));
    const double diag_mean = hstest::mean_diagonal(K);
    int compared = 0;
    for (const double shift : {0.0, 0.15, 0.2, 0.3, 0.45, 0.6}) {
      INFO("P" << degree << ", shift " << shift << " x mean diagonal");
      core::MatH A, S;
      HS_PETSC(MatDuplicate(K, MAT_COPY_VALUES, A.out()));
      HS_PETSC(MatShift(A, -shift * diag_mean));
      HS_PETSC(MatSetOption(A, MAT_SYMMETRIC, PETSC_TRUE));  // (SBAIJ keeps the upper triangle)
      HS_PETSC(MatConvert(A, MATSEQSBAIJ, MAT_INITIAL_MATRIX, S.out()));
      PetscInt bs;
      HS_PETSC(MatGetBlockSize(S, &bs));
      REQUIRE(bs == 2);
      core::KSPH ksp = petsc_factor(S);
      PC pc;
      PCFailedReason why;
      HS_PETSC(KSPGetPC(ksp, &pc));
      HS_PETSC(PCGetFailedReason(pc, &why));
      solver::BlockLdlt2 own;
      const bool ok = own_factor(S, own);
      CHECK(ok == (why == PC_NOERROR));
      if (!ok) continue;  // (P2 at 0.2, 0.45, 0.6 here: a zero pivot, in both)
      ++compared;
      CHECK(own.negative_eigenvalues() == solver::negative_eigenvalues(ksp));
      if (shift == 0.6) CHECK(own.negative_eigenvalues() > 0);
      // Two right-hand sides: the load, and a vector with every entry nonzero.
      core::VecH b2 = p.create_vector();
      HS_PETSC(VecCopy(p.load(), b));
      PetscInt lo, hi;
      HS_PETSC(VecGetOwnershipRange(b2, &lo, &hi));
      for (PetscInt i = lo; i < hi; ++i) HS_PETSC(VecSetValue(b2, i, 1.0 + 0.37 * double(i % 7) - 0.11 * double(i % 5), INSERT_VALUES));
      HS_PETSC(VecAssemblyBegin(b2));
      HS_PETSC(VecAssemblyEnd(b2));
      std::vector<std::vector<double>> ours;
      for (Vec rhs : {Vec(b), Vec(b2)}) {
        HS_PETSC(KSPSolve(ksp, rhs, x));
        const std::vector<double> theirs = values(x);
        ours.push_back(values(rhs));
        own.solve(ours.back().data());
        REQUIRE(ours.back().size() == theirs.size());
        CHECK(std::memcmp(ours.back().data(), theirs.data(), theirs.size() * sizeof(double)) == 0);
      }
      // Both at once, interleaved by node: each one's numbers as alone.
      const std::vector<double> v1 = values(b), v2 = values(b2);
      std::vector<double> both(2 * v1.size());
      for (std::size_t k = 0; 2 * k < v1.size(); ++k)
        both[4 * k] = v1[2 * k], both[4 * k + 1] = v1[2 * k + 1], both[4 * k + 2] = v2[2 * k], both[4 * k + 3] = v2[2 * k + 1];
      own.solve2(both.data());
      bool same = true;
      for (std::size_t k = 0; 2 * k < v1.size(); ++k)
        for (int i = 0; i < 2; ++i)
          same = same && std::memcmp(&both[4 * k + i], &ours[0][2 * k + i], sizeof(double)) == 0 &&
                 std::memcmp(&both[4 * k + 2 + i], &ours[1][2 * k + i], sizeof(double)) == 0;
      CHECK(same);
    }
    CHECK(compared >= 3);
  }
}

TEST_CASE("BlockLdlt2 fails where PETSc's factorisation meets a zero pivot", "[solver]") {
  // Two nodes; node 0's block [[1, 1], [1, 1]] is singular (its second pivot is exactly zero).
  core::MatH S;
  HS_PETSC(MatCreateSeqSBAIJ(PETSC_COMM_SELF, 2, 4, 4, 2, nullptr, S.out()));
  const PetscInt r0 = 0, r1 = 1;
  const PetscScalar singular[4] = {1, 1, 1, 1}, coupling[4] = {0.5, 0, 0, 0.5}, regular[4] = {4, 0, 0, 4};
  HS_PETSC(MatSetValuesBlocked(S, 1, &r0, 1, &r0, singular, INSERT_VALUES));
  HS_PETSC(MatSetValuesBlocked(S, 1, &r0, 1, &r1, coupling, INSERT_VALUES));
  HS_PETSC(MatSetValuesBlocked(S, 1, &r1, 1, &r1, regular, INSERT_VALUES));
  HS_PETSC(MatAssemblyBegin(S, MAT_FINAL_ASSEMBLY));
  HS_PETSC(MatAssemblyEnd(S, MAT_FINAL_ASSEMBLY));
  core::KSPH ksp = petsc_factor(S);
  PC pc;
  PCFailedReason why;
  HS_PETSC(KSPGetPC(ksp, &pc));
  HS_PETSC(PCGetFailedReason(pc, &why));
  CHECK(why != PC_NOERROR);
  solver::BlockLdlt2 own;
  CHECK_FALSE(own_factor(S, own));
  // Refactorised with a regular first block, it succeeds: the failed factorisation left its work
  // arrays clean.
  PetscScalar* v;
  HS_PETSC(MatSeqSBAIJGetArray(S, &v));
  v[0] = 2;  // [[2, 1], [1, 1]]
  CHECK(own.factorise(v));
  HS_PETSC(MatSeqSBAIJRestoreArray(S, &v));
  CHECK(own.negative_eigenvalues() == 0);
}

TEST_CASE("The blocked LDL^T's paired solve gives each solve's numbers", "[solver]") {
  // The corrector solves K a = f and K b = R with one pass over the factor (solve_pair): the
  // same bits as two solves, through the node ordering and the refinement.
  physics::Problem p{PETSC_COMM_WORLD, hstest::disk_mesh(0.15), hstest::disk_effects(), hstest::degree(2)};
  core::VecH u = p.create_vector(), r = p.create_vector(), a1 = p.create_vector(), b1 = p.create_vector(),
             a2 = p.create_vector(), b2 = p.create_vector();
  HS_PETSC(VecCopy(p.load(), u));
  HS_PETSC(VecScale(u, 0.02));
  REQUIRE(p.residual(u, 1.0, r));
  core::MatH K = p.create_matrix();
  REQUIRE(p.jacobian(u, K));
  solver::LdltFactor f(p, "");
  REQUIRE(f.factorise(K));
  REQUIRE(f.blocked());
  REQUIRE(f.solve(p.load(), a1));
  REQUIRE(f.solve(r, b1));
  REQUIRE(f.solve_pair(p.load(), a2, r, b2));
  const std::vector<double> va1 = values(a1), va2 = values(a2), vb1 = values(b1), vb2 = values(b2);
  CHECK(std::memcmp(va1.data(), va2.data(), va1.size() * sizeof(double)) == 0);
  CHECK(std::memcmp(vb1.data(), vb2.data(), vb1.size() * sizeof(double)) == 0);
  CHECK(std::abs(vb1[0]) + std::abs(vb1.back()) > 0);  // not two zero vectors
}

TEST_CASE("The blocked factor's node ordering is PETSc's AMD ordering of the matrix as BAIJ", "[solver]") {
  // amd_node_ordering calls SuiteSparse's AMD on the block graph itself; the factors' data rest on
  // it being the permutation MatGetOrdering gave for the BAIJ conversion it replaced.
  int ranks;
  MPI_Comm_size(PETSC_COMM_WORLD, &ranks);
  if (ranks != 1) return;  // (the blocked factor is serial)
  for (const int degree : {1, 2})
    for (const double h : {0.2, 0.07}) {
      INFO("P" << degree << ", h " << h);
      physics::Problem p{PETSC_COMM_WORLD, hstest::disk_mesh(h), hstest::disk_effects(), hstest::degree(degree)};
      core::MatH K = p.create_matrix(), B;
      core::VecH u = p.create_vector();
      HS_PETSC(VecCopy(p.load(), u));
      HS_PETSC(VecScale(u, 0.02));
      REQUIRE(p.jacobian(u, K));
      HS_PETSC(MatConvert(K, MATSEQBAIJ, MAT_INITIAL_MATRIX, B.out()));
      core::ISH rp, cp;
      HS_PETSC(MatGetOrdering(B, MATORDERINGAMD, rp.out(), cp.out()));
      PetscInt nb;
      HS_PETSC(ISGetSize(rp, &nb));
      const PetscInt* r;
      HS_PETSC(ISGetIndices(rp, &r));
      const std::vector<PetscInt> theirs(r, r + nb);
      HS_PETSC(ISRestoreIndices(rp, &r));
      const std::vector<PetscInt> ours = solver::amd_node_ordering(K);
      PetscInt n;
      HS_PETSC(MatGetSize(K, &n, nullptr));
      REQUIRE(nb == n / 2);
      CHECK(ours == theirs);
      std::vector<PetscInt> identity(std::size_t(nb), 0);
      for (PetscInt i = 0; i < nb; ++i) identity[std::size_t(i)] = i;
      CHECK(ours != identity);  // a real reordering
    }
}

TEST_CASE("The factor's arrays are allocated on cache lines", "[solver]") {
  // BlockLdlt2 reads and writes 32-byte blocks; on malloc's 16-byte boundaries every other one
  // straddles two cache lines (a tenth of the factorisation's time, docs/PERFORMANCE.md).
  for (std::size_t n : {1, 3, 4, 1000, 123457}) {
    solver::AlignedDoubles v(n, 1.0);
    CHECK(reinterpret_cast<std::uintptr_t>(v.data()) % 64 == 0);
    v.resize(2 * n + 5);
    CHECK(reinterpret_cast<std::uintptr_t>(v.data()) % 64 == 0);
  }
}

TEST_CASE("The blocked LDL^T's solve with |D| is a positive definite solve, and the plain one where D is", "[solver]") {
  // The corrector's modified Newton step (-path_absolute_pivots): U^T |D| U x = b. On an
  // indefinite matrix x . b > 0 for every b (a descent direction), where the plain solve's is
  // negative for some; on a positive definite one, the plain solve's numbers (before refinement).
  physics::Problem p{PETSC_COMM_WORLD, hstest::disk_mesh(0.15), hstest::disk_effects(), hstest::degree(2)};
  core::MatH K = p.create_matrix();
  core::VecH u = p.create_vector(), b = p.create_vector(), x = p.create_vector(), y = p.create_vector(),
             x2 = p.create_vector(), y2 = p.create_vector();
  REQUIRE(p.jacobian(u, K));
  solver::LdltFactor f(p, "");
  REQUIRE(f.factorise(K));
  REQUIRE(f.has_absolute());
  REQUIRE(f.negative_eigenvalues() == 0);
  HS_PETSC(VecSetRandom(b, nullptr));
  REQUIRE(f.solve_pair(b, x, p.load(), y, true));
  REQUIRE(f.solve_pair(b, x2, p.load(), y2));
  PetscReal diff, norm;
  HS_PETSC(VecAXPY(x2, -1.0, x));
  HS_PETSC(VecNorm(x2, NORM_INFINITY, &diff));
  HS_PETSC(VecNorm(x, NORM_INFINITY, &norm));
  CHECK(diff <= 1e-9 * norm);
  // Indefinite: K - sigma I with sigma a tenth of the mean diagonal.
  core::VecH d = p.create_vector();
  HS_PETSC(MatGetDiagonal(K, d));
  PetscReal sum;
  PetscInt n;
  HS_PETSC(VecSum(d, &sum));
  HS_PETSC(VecGetSize(d, &n));
  HS_PETSC(MatShift(K, -0.1 * sum / PetscReal(n)));
  REQUIRE(f.factorise(K));
  REQUIRE(f.negative_eigenvalues() > 0);
  int plain_ascent = 0;
  for (int k = 0; k < 10; ++k) {
    HS_PETSC(VecSetRandom(b, nullptr));
    HS_PETSC(VecShift(b, -0.5));
    REQUIRE(f.solve_pair(b, x, p.load(), y, true));
    REQUIRE(f.solve_pair(b, x2, p.load(), y2));
    PetscReal bx, bx2;
    HS_PETSC(VecDot(b, x, &bx));
    HS_PETSC(VecDot(b, x2, &bx2));
    CHECK(bx > 0);
    plain_ascent += bx2 < 0;
  }
  CHECK(plain_ascent > 0);
}
