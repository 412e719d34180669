#include "hypershape/solver/ldlt.hpp"

#include <petscmat.h>
#include <suitesparse/amd.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>

#include "hypershape/core/error.hpp"
#include "hypershape/core/vec_array.hpp"
#include "log_events.hpp"

namespace hypershape::solver {

namespace {

/// Negative eigenvalues of PETSc's blocked U^T D U factor of 2x2 blocks: PETSc 3.18 stores D_k^-1
/// as the first n/2 blocks of the factor's values, the blocks of U after them.
int petsc_negative_eigenvalues_2x2(Mat F) {
  PetscInt n;
  HS_PETSC(MatGetSize(F, &n, nullptr));
  PetscScalar* v;
  HS_PETSC(MatSeqSBAIJGetArray(F, &v));
  const int neg = negative_eigenvalues_2x2(v, n / 2);
  HS_PETSC(MatSeqSBAIJRestoreArray(F, &v));
  return neg;
}

bool option_given(const std::string& prefix, const char* name) {
  PetscBool set = PETSC_FALSE;
  HS_PETSC(PetscOptionsHasName(nullptr, prefix.empty() ? nullptr : prefix.c_str(), name, &set));
  return set;
}

}  // namespace

int negative_eigenvalues(KSP ksp) {
  PC pc;
  PCType type;
  HS_PETSC(KSPGetPC(ksp, &pc));
  HS_PETSC(PCGetType(pc, &type));
  if (!type || std::string(type) != PCCHOLESKY) return -1;
  MatSolverType package;
  Mat F;
  HS_PETSC(PCFactorGetMatSolverType(pc, &package));
  HS_PETSC(PCFactorGetMatrix(pc, &F));
  const std::string p = package ? package : "";
  PetscInt neg = -1, zero, pos, bs = 1;
  if (p == MATSOLVERMUMPS) {
    HS_PETSC(MatMumpsGetInfog(F, 12, &neg));
  } else if (p == MATSOLVERPETSC) {
    HS_PETSC(MatGetBlockSize(F, &bs));
    if (bs == 2) return petsc_negative_eigenvalues_2x2(F);
    if (bs == 1) HS_PETSC(MatGetInertia(F, &neg, &zero, &pos));
  }
  return int(neg);
}

void configure_direct_solver(KSP ksp, MPI_Comm comm, int dim, bool symmetric) {
  PC pc;
  HS_PETSC(KSPSetType(ksp, KSPPREONLY));
  HS_PETSC(KSPGetPC(ksp, &pc));
  HS_PETSC(PCSetType(pc, symmetric ? PCCHOLESKY : PCLU));
  // 2D on one rank: PETSc's own sparse Cholesky (LDL^T without pivoting); measured 1.4x faster
  // per load case than MUMPS on Random2D shapes, whose per-call overhead dominates at a few
  // thousand unknowns. In 3D its non-supernodal factorisation is far slower than MUMPS (a
  // Random3D load case took minutes), and a solver group of several ranks needs a parallel one:
  // MUMPS. Both report the inertia.
  PetscMPIInt ranks;
  MPI_Comm_size(comm, &ranks);
  if (ranks == 1 && dim == 2) {
    HS_PETSC(PCFactorSetMatSolverType(pc, MATSOLVERPETSC));
    HS_PETSC(PCFactorSetMatOrderingType(pc, symmetric ? MATORDERINGQMD : MATORDERINGND));
  } else {
    HS_PETSC(PCFactorSetMatSolverType(pc, MATSOLVERMUMPS));
  }
}

core::KSPH make_factor_preconditioned_gmres(MPI_Comm comm, void* ctx, PetscErrorCode (*apply)(PC, Vec, Vec),
                                            const char* name) {
  core::KSPH ksp;
  HS_PETSC(KSPCreate(comm, ksp.out()));
  HS_PETSC(KSPSetType(ksp, KSPGMRES));
  HS_PETSC(KSPSetPCSide(ksp, PC_RIGHT));
  PC pc;
  HS_PETSC(KSPGetPC(ksp, &pc));
  HS_PETSC(PCSetType(pc, PCSHELL));
  HS_PETSC(PCShellSetContext(pc, ctx));
  HS_PETSC(PCShellSetApply(pc, apply));
  HS_PETSC(PCShellSetName(pc, name));
  return ksp;
}

LdltFactor::LdltFactor(const physics::Problem& problem, const std::string& prefix, bool symmetric, bool single)
    : symmetric_(symmetric) {
  HS_PETSC(KSPCreate(problem.comm(), ksp_.out()));
  if (!prefix.empty()) HS_PETSC(KSPSetOptionsPrefix(ksp_, prefix.c_str()));
  configure_direct_solver(ksp_, problem.comm(), problem.space().dim(), symmetric);
  // The blocked kind where PETSc's own factorisation is used and no option asks for another
  // (the options keep their meaning: the general kind reads them).
  PetscMPIInt ranks;
  MPI_Comm_size(problem.comm(), &ranks);
  const bool own_kind = symmetric && ranks == 1 && !option_given(prefix, "-pc_factor_mat_solver_type") &&
                        !option_given(prefix, "-pc_factor_mat_ordering_type") && !option_given(prefix, "-pc_type") &&
                        !option_given(prefix, "-ksp_type");
  if (own_kind && single) {
    single_ = std::make_unique<SingleFactor>();
    return;
  }
  // The blocked kind factorises with block_ (ksp_ is the general kind's).
  blocked_ = own_kind && problem.space().dim() == 2;
  if (!blocked_) HS_PETSC(KSPSetFromOptions(ksp_));
}

void LdltFactor::set_up_blocked(Mat A) {
  PetscInt n, bs;
  MatType type;
  HS_PETSC(MatGetSize(A, &n, nullptr));
  HS_PETSC(MatGetBlockSize(A, &bs));
  HS_PETSC(MatGetType(A, &type));
  if (bs != 2 || n % 2 != 0 || std::string(type) != MATSEQAIJ) {  // not a 2D vector field: general
    blocked_ = false;
    HS_PETSC(KSPSetFromOptions(ksp_));
    return;
  }
  const std::vector<PetscInt> new_block = node_ordering(A);
  build_block_pattern(A, new_block);
  HS_PETSC(VecCreateSeq(PETSC_COMM_SELF, n, xp_.out()));
  HS_PETSC(VecDuplicate(xp_, yp_.out()));
  HS_PETSC(VecDuplicate(xp_, rp_.out()));
  HS_PETSC(VecDuplicate(xp_, xp2_.out()));
  HS_PETSC(VecDuplicate(xp_, yp2_.out()));
  pair_.resize(2 * std::size_t(n));
}

std::vector<PetscInt> amd_node_ordering(Mat A) {
  // Called as PETSc's MatGetOrdering_AMD calls it on a BAIJ matrix: the block rows' sorted
  // columns, diagonal included, AMD's defaults. (MatConvert to BAIJ cost about 2.5% of a Random2D P1 run.)
  static_assert(sizeof(PetscInt) == sizeof(int), "amd_order takes int indices (amd_l_order for 64-bit)");
  PetscInt n, nr;
  HS_PETSC(MatGetSize(A, &n, nullptr));
  const PetscInt nb = n / 2;
  const PetscInt *ia, *ja;
  PetscBool done;
  HS_PETSC(MatGetRowIJ(A, 0, PETSC_FALSE, PETSC_FALSE, &nr, &ia, &ja, &done));
  if (!done) throw std::logic_error("blocked LDL^T: no row structure of the matrix");
  if (nr != n || n % 2 != 0) {
    HS_PETSC(MatRestoreRowIJ(A, 0, PETSC_FALSE, PETSC_FALSE, &nr, &ia, &ja, &done));
    throw std::logic_error("blocked LDL^T: the matrix's rows are not node pairs");
  }
  std::vector<PetscInt> bi(std::size_t(nb) + 1, 0), bj, row;
  bj.reserve(std::size_t(ia[n]) / 2);
  for (PetscInt b = 0; b < nb; ++b) {
    row.clear();
    for (PetscInt k = ia[2 * b]; k < ia[2 * b + 2]; ++k) row.push_back(ja[k] / 2);
    std::sort(row.begin(), row.end());
    row.erase(std::unique(row.begin(), row.end()), row.end());
    bj.insert(bj.end(), row.begin(), row.end());
    bi[std::size_t(b) + 1] = PetscInt(bj.size());
  }
  HS_PETSC(MatRestoreRowIJ(A, 0, PETSC_FALSE, PETSC_FALSE, &nr, &ia, &ja, &done));
  double control[AMD_CONTROL], info[AMD_INFO];
  amd_defaults(control);
  std::vector<PetscInt> perm(static_cast<std::size_t>(nb));
  const int status = amd_order(nb, bi.data(), bj.data(), perm.data(), control, info);
  if (status != AMD_OK) throw std::runtime_error("AMD ordering of the tangent's node graph failed (status " + std::to_string(status) + ")");
  return perm;
}

std::vector<PetscInt> LdltFactor::node_ordering(Mat A) {
  PetscInt n;
  HS_PETSC(MatGetSize(A, &n, nullptr));
  const PetscInt nb = n / 2;
  // A fill-reducing ordering of the nodes: approximate minimum degree on the 2x2-block graph.
  // (PETSc's nested dissection instead made the factorisations 1.7x (P1 h 0.04) and 3.3x (P2
  // h 0.12) slower on Random2D slices, measured side by side with scripts/bench_versions.sh.)
  const std::vector<PetscInt> perm = amd_node_ordering(A);
  std::vector<PetscInt> new_block(static_cast<std::size_t>(nb));
  old_of_new_.resize(static_cast<std::size_t>(n));
  for (PetscInt i = 0; i < nb; ++i) {
    const PetscInt r = perm[std::size_t(i)];
    new_block[std::size_t(r)] = i;
    old_of_new_[std::size_t(2 * i)] = 2 * r;
    old_of_new_[std::size_t(2 * i + 1)] = 2 * r + 1;
  }
  return new_block;
}

void LdltFactor::build_block_pattern(Mat A, const std::vector<PetscInt>& new_block) {
  PetscInt n;
  HS_PETSC(MatGetSize(A, &n, nullptr));
  const PetscInt nb = n / 2;
  // The upper block pattern in the new ordering, then where each value of A goes in it.
  const PetscInt *ia, *ja;
  PetscInt nr;
  PetscBool done;
  HS_PETSC(MatGetRowIJ(A, 0, PETSC_FALSE, PETSC_FALSE, &nr, &ia, &ja, &done));
  std::vector<std::vector<PetscInt>> cols(static_cast<std::size_t>(nb));
  for (PetscInt i = 0; i < n; ++i)
    for (PetscInt k = ia[i]; k < ia[i + 1]; ++k) {
      const PetscInt bi = new_block[std::size_t(i / 2)], bj = new_block[std::size_t(ja[k] / 2)];
      if (bi <= bj) cols[std::size_t(bi)].push_back(bj);
    }
  std::vector<PetscInt> nnz(static_cast<std::size_t>(nb));
  for (PetscInt b = 0; b < nb; ++b) {
    auto& c = cols[std::size_t(b)];
    std::sort(c.begin(), c.end());
    c.erase(std::unique(c.begin(), c.end()), c.end());
    nnz[std::size_t(b)] = PetscInt(c.size());
  }
  HS_PETSC(MatCreateSeqSBAIJ(PETSC_COMM_SELF, 2, n, n, 0, nnz.data(), F_.out()));
  const std::array<PetscScalar, 4> zero{};
  for (PetscInt b = 0; b < nb; ++b)
    for (PetscInt c : cols[std::size_t(b)]) HS_PETSC(MatSetValuesBlocked(F_, 1, &b, 1, &c, zero.data(), INSERT_VALUES));
  HS_PETSC(MatAssemblyBegin(F_, MAT_FINAL_ASSEMBLY));
  HS_PETSC(MatAssemblyEnd(F_, MAT_FINAL_ASSEMBLY));
  const PetscInt *fi, *fj;
  PetscInt nfr;
  HS_PETSC(MatGetRowIJ(F_, 0, PETSC_FALSE, PETSC_TRUE, &nfr, &fi, &fj, &done));
  if (std::int64_t(ia[n]) > std::int64_t(UINT32_MAX)) throw std::logic_error("blocked LDL^T: more nonzeros than 32-bit offsets hold");
  std::vector<std::pair<std::uint32_t, std::uint32_t>> to_from;  // (position in F_, in A)
  for (PetscInt i = 0; i < n; ++i)
    for (PetscInt k = ia[i]; k < ia[i + 1]; ++k) {
      const PetscInt bi = new_block[std::size_t(i / 2)], bj = new_block[std::size_t(ja[k] / 2)];
      if (bi > bj) continue;
      const PetscInt q = PetscInt(std::lower_bound(fj + fi[bi], fj + fi[bi + 1], bj) - fj);
      to_from.emplace_back(std::uint32_t(4 * q + 2 * (ja[k] % 2) + i % 2), std::uint32_t(k));  // blocks are column-major
    }
  std::sort(to_from.begin(), to_from.end());
  block_.analyse(nb, fi, fj);
  source_.resize(to_from.size());
  target_.resize(to_from.size());
  for (std::size_t k = 0; k < to_from.size(); ++k) std::tie(target_[k], source_[k]) = to_from[k];
  HS_PETSC(MatRestoreRowIJ(F_, 0, PETSC_FALSE, PETSC_TRUE, &nfr, &fi, &fj, &done));
  HS_PETSC(MatRestoreRowIJ(A, 0, PETSC_FALSE, PETSC_FALSE, &nr, &ia, &ja, &done));
}

void LdltFactor::scatter_values(Mat A) {
  const PetscScalar* av;
  PetscScalar* fv;
  HS_PETSC(MatSeqAIJGetArrayRead(A, &av));
  HS_PETSC(MatSeqSBAIJGetArray(F_, &fv));
  for (std::size_t k = 0; k < target_.size(); ++k) fv[target_[k]] = av[source_[k]];
  HS_PETSC(MatSeqSBAIJRestoreArray(F_, &fv));
  HS_PETSC(MatSeqAIJRestoreArrayRead(A, &av));
  // (No MatAssemblyBegin/End: the pattern is assembled once, and restoring the array raised
  // F_'s state, which is all its product, the refinement's residual, reads. Removed as work
  // nothing needed; its own cost was within the noise of a 4 x 25 P2 run.)
}

bool LdltFactor::factorise(Mat A) {
  if (single_) {
    analysed_ = true;
    return factored_ = single_->factorise(A);
  }
  if (!analysed_ && blocked_) set_up_blocked(A);
  analysed_ = true;
  if (!blocked_ && !F_) {
    HS_PETSC(MatDuplicate(A, MAT_DO_NOT_COPY_VALUES, F_.out()));
    HS_PETSC(MatSetOption(F_, MAT_SYMMETRIC, symmetric_ ? PETSC_TRUE : PETSC_FALSE));
    HS_PETSC(MatSetOption(F_, MAT_SYMMETRY_ETERNAL, symmetric_ ? PETSC_TRUE : PETSC_FALSE));
  }
  if (blocked_) {
    scatter_values(A);
    LogEvent event(events().blocked_factor);
    PetscScalar* fv;
    HS_PETSC(MatSeqSBAIJGetArray(F_, &fv));
    factored_ = block_.factorise(fv);
    HS_PETSC(MatSeqSBAIJRestoreArray(F_, &fv));
    HS_PETSC(PetscLogFlops(16.0 * double(block_.factor_blocks()) + 11.0 * double(block_.blocks())));
    return factored_;
  }
  HS_PETSC(MatCopy(A, F_, SAME_NONZERO_PATTERN));
  // PCSetUp factorises now (not at the first solve), so that a failure is seen here.
  PC pc;
  PCFailedReason why;
  HS_PETSC(KSPSetOperators(ksp_, F_, F_));
  HS_PETSC(KSPGetPC(ksp_, &pc));
  HS_PETSC(PCSetUp(pc));
  HS_PETSC(PCGetFailedReason(pc, &why));
  factored_ = why == PC_NOERROR;
  return factored_;
}

bool LdltFactor::solve(Vec b, Vec x) {
  if (single_) return single_->solve(b, x);
  KSPConvergedReason r;
  if (!blocked_) {
    HS_PETSC(KSPSolve(ksp_, b, x));
    HS_PETSC(KSPGetConvergedReason(ksp_, &r));
    return r > 0;
  }
  to_new(b, xp_);
  block_solve(xp_, yp_);
  refine(xp_, yp_);
  to_old(yp_, x);
  return true;
}

bool LdltFactor::solve_pair(Vec b1, Vec x1, Vec b2, Vec x2, bool absolute) {
  if (!blocked_) return solve(b1, x1) && solve(b2, x2);
  to_new(b1, xp_);
  to_new(b2, xp2_);
  {
    core::VecArray<const PetscScalar> p1(xp_), p2(xp2_);
    for (std::size_t k = 0; 2 * k < old_of_new_.size(); ++k) {
      const auto i = PetscInt(2 * k);
      pair_[4 * k] = p1[i], pair_[4 * k + 1] = p1[i + 1], pair_[4 * k + 2] = p2[i], pair_[4 * k + 3] = p2[i + 1];
    }
  }
  if (absolute) block_.solve2_absolute(pair_.data());
  else block_.solve2(pair_.data());
  {
    core::VecArray<PetscScalar> y1(yp_), y2(yp2_);
    for (std::size_t k = 0; 2 * k < old_of_new_.size(); ++k) {
      const auto i = PetscInt(2 * k);
      y1[i] = pair_[4 * k], y1[i + 1] = pair_[4 * k + 1], y2[i] = pair_[4 * k + 2], y2[i + 1] = pair_[4 * k + 3];
    }
  }
  if (!absolute) refine(xp_, yp_);  // (refinement would take U^T |D| U's solutions back to A's)
  to_old(yp_, x1);
  if (!absolute) refine(xp2_, yp2_);
  to_old(yp2_, x2);
  return true;
}

void LdltFactor::to_new(Vec b, Vec bp) const {
  core::VecArray<const PetscScalar> bv(b);
  core::VecArray<PetscScalar> pv(bp);
  for (std::size_t i = 0; i < old_of_new_.size(); ++i) pv[PetscInt(i)] = bv[old_of_new_[i]];
}

void LdltFactor::to_old(Vec yp, Vec x) const {
  core::VecArray<const PetscScalar> yv(yp);
  core::VecArray<PetscScalar> xv(x);
  for (std::size_t i = 0; i < old_of_new_.size(); ++i) xv[old_of_new_[i]] = yv[PetscInt(i)];
}

void LdltFactor::block_solve(Vec x, Vec y) const {
  if (x != y) HS_PETSC(VecCopy(x, y));
  core::VecArray<PetscScalar> yv(y);
  block_.solve(&yv[0]);
}

PetscErrorCode LdltFactor::apply_factor(PC pc, Vec x, Vec y) {
  void* ctx;
  PetscFunctionBeginUser;
  PetscCall(PCShellGetContext(pc, &ctx));
  try {  // (no exception through PETSc's frames)
    static_cast<LdltFactor*>(ctx)->block_solve(x, y);
  } catch (const std::exception& e) {
    SETERRQ(PETSC_COMM_SELF, PETSC_ERR_LIB, "blocked LDL^T solve: %s", e.what());
  }
  PetscFunctionReturn(0);
}

void LdltFactor::refine(Vec b, Vec y) {
  // Without pivoting, an LDL^T of an indefinite matrix can lose digits to small pivots (seen in
  // this ordering on shifted tangents: relative residuals up to 0.25 where the scalar qmd factor
  // kept 1e-12). Where the residual shows it, GMRES preconditioned by the factor, from the
  // factor's solution, restores them; where the factor is accurate this costs one product.
  PetscReal bn, rn;
  HS_PETSC(VecNorm(b, NORM_2, &bn));
  HS_PETSC(MatMult(F_, y, rp_));
  HS_PETSC(VecAYPX(rp_, -1.0, b));
  HS_PETSC(VecNorm(rp_, NORM_2, &rn));
  constexpr double rtol = 1e-10;
  if (!(rn > rtol * bn)) return;
  if (!refine_) {
    refine_ = make_factor_preconditioned_gmres(PETSC_COMM_SELF, this, apply_factor, "LDL^T factor (refinement)");
    HS_PETSC(KSPSetInitialGuessNonzero(refine_, PETSC_TRUE));
  }
  HS_PETSC(KSPSetOperators(refine_, F_, F_));
  HS_PETSC(KSPSetTolerances(refine_, 1e-30, rtol * bn, PETSC_DEFAULT, 30));
  HS_PETSC(KSPSolve(refine_, b, y));  // not converged in 30: the best it found (Newton judges)
}

int LdltFactor::negative_eigenvalues() const {
  if (single_) return single_->negative_eigenvalues();
  if (!factored_) return -1;
  return blocked_ ? block_.negative_eigenvalues() : solver::negative_eigenvalues(ksp_);
}

}  // namespace hypershape::solver
