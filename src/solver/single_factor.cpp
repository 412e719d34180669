#include "hypershape/solver/single_factor.hpp"

#include <smumps_c.h>

#include <cmath>
#include <stdexcept>
#include <string>

#include "hypershape/core/error.hpp"
#include "hypershape/core/vec_array.hpp"
#include "hypershape/solver/ldlt.hpp"
#include "log_events.hpp"

namespace hypershape::solver {

struct SingleFactor::Mumps {
  SMUMPS_STRUC_C id{};
  std::vector<MUMPS_INT> irn, jcn;
  bool initialised = false;
  void run(int job) {
    id.job = job;
    smumps_c(&id);
  }
  int error() const { return id.infog[0]; }  // INFOG(1): < 0 failed
};

SingleFactor::SingleFactor() : m_(std::make_unique<Mumps>()) {
  auto& id = m_->id;
  id.comm_fortran = MUMPS_INT(MPI_Comm_c2f(PETSC_COMM_SELF));
  id.par = 1;  // the host works
  id.sym = 2;  // symmetric, possibly indefinite: LDL^T with 2x2 pivots
  m_->run(-1);
  if (m_->error() < 0) throw std::runtime_error("SMUMPS initialisation failed, INFOG(1) = " + std::to_string(m_->error()));
  m_->initialised = true;
  id.icntl[0] = id.icntl[1] = id.icntl[2] = -1;  // no messages
  id.icntl[3] = 0;
}

SingleFactor::~SingleFactor() {
  if (m_->initialised) m_->run(-2);
}

void SingleFactor::analyse(Mat A) {
  PetscInt n, m;
  const PetscInt *ia, *ja;
  PetscBool done;
  HS_PETSC(MatGetRowIJ(A, 0, PETSC_FALSE, PETSC_FALSE, &n, &ia, &ja, &done));
  if (!done) throw std::logic_error("SingleFactor: not a sequential AIJ matrix");
  for (PetscInt i = 0; i < n; ++i)
    for (PetscInt k = ia[i]; k < ia[i + 1]; ++k)
      if (ja[k] >= i) {  // the upper triangle, 1-based coordinates
        upper_.push_back(k);
        m_->irn.push_back(MUMPS_INT(i + 1));
        m_->jcn.push_back(MUMPS_INT(ja[k] + 1));
      }
  HS_PETSC(MatRestoreRowIJ(A, 0, PETSC_FALSE, PETSC_FALSE, &m, &ia, &ja, &done));  // (it zeroes its n)
  values_.resize(upper_.size());
  rhs_.resize(std::size_t(n));
  auto& id = m_->id;
  id.n = MUMPS_INT(n);
  id.nnz = MUMPS_INT8(upper_.size());
  id.irn = m_->irn.data();
  id.jcn = m_->jcn.data();
  m_->run(1);
  if (m_->error() < 0) throw std::runtime_error("SMUMPS analysis failed, INFOG(1) = " + std::to_string(m_->error()));
  HS_PETSC(MatCreateVecs(A, r_.out(), d_.out()));
  analysed_ = true;
}

bool SingleFactor::factorise(Mat A) {
  if (!analysed_) analyse(A);
  if (!A_) HS_PETSC(MatDuplicate(A, MAT_COPY_VALUES, A_.out()));
  else HS_PETSC(MatCopy(A, A_, SAME_NONZERO_PATTERN));
  {
    const PetscScalar* a;
    HS_PETSC(MatSeqAIJGetArrayRead(A_, &a));
    for (std::size_t k = 0; k < upper_.size(); ++k) values_[k] = float(a[upper_[k]]);
    HS_PETSC(MatSeqAIJRestoreArrayRead(A_, &a));
  }
  m_->id.a = values_.data();
  LogEvent e(events().single_factor);
  // Out of workspace (INFOG(1) -8/-9: the pivots' 2x2 blocks and delays outgrew the estimate):
  // twice and four times the relaxation, as MUMPS's guide advises.
  for (int relax = 20; ; relax *= 2) {
    m_->id.icntl[13] = relax;  // ICNTL(14): % workspace above the analysis' estimate
    m_->run(2);
    if (!(m_->error() == -8 || m_->error() == -9) || relax >= 80) break;
  }
  factored_ = m_->error() >= 0;
  negative_ = factored_ ? int(m_->id.infog[11]) : -1;  // INFOG(12): negative pivots
  return factored_;
}

void SingleFactor::solve_single(Vec r, Vec d) {
  {
    core::VecArray<const PetscScalar> rv(r);
    for (std::size_t i = 0; i < rhs_.size(); ++i) rhs_[i] = float(rv[PetscInt(i)]);
  }
  m_->id.rhs = rhs_.data();
  m_->run(3);
  core::VecArray<PetscScalar> dv(d);
  for (std::size_t i = 0; i < rhs_.size(); ++i) dv[PetscInt(i)] = rhs_[i];
  ++steps_;
}

PetscErrorCode SingleFactor::apply(PC pc, Vec x, Vec y) {
  void* ctx;
  PetscFunctionBeginUser;
  PetscCall(PCShellGetContext(pc, &ctx));
  try {
    static_cast<SingleFactor*>(ctx)->solve_single(x, y);
  } catch (const std::exception& e) {
    SETERRQ(PETSC_COMM_SELF, PETSC_ERR_LIB, "%s", e.what());
  }
  PetscFunctionReturn(0);
}

bool SingleFactor::solve_unrefined(Vec b, Vec x) {
  steps_ = 0;
  if (!factored_) return false;
  solve_single(b, x);
  PetscReal n;
  HS_PETSC(VecNorm(x, NORM_2, &n));
  return std::isfinite(n);
}

bool SingleFactor::solve(Vec b, Vec x) {
  steps_ = 0;
  if (!factored_) return false;
  constexpr double rtol = 1e-10;
  PetscReal bn, rn, last = PETSC_MAX_REAL;
  HS_PETSC(VecNorm(b, NORM_2, &bn));
  HS_PETSC(VecSet(x, 0.0));
  HS_PETSC(VecCopy(b, r_));
  for (int k = 0; k < 10; ++k) {
    solve_single(r_, d_);
    HS_PETSC(VecAXPY(x, 1.0, d_));
    HS_PETSC(MatMult(A_, x, r_));
    HS_PETSC(VecAYPX(r_, -1.0, b));
    HS_PETSC(VecNorm(r_, NORM_2, &rn));
    if (!std::isfinite(rn)) return false;
    if (rn <= rtol * bn) return true;
    if (rn > 0.5 * last) break;  // stagnates: GMRES from here
    last = rn;
  }
  if (!gmres_) {
    gmres_ = make_factor_preconditioned_gmres(PETSC_COMM_SELF, this, apply, "single-precision LDL^T (refinement)");
    HS_PETSC(KSPSetInitialGuessNonzero(gmres_, PETSC_TRUE));
  }
  HS_PETSC(KSPSetOperators(gmres_, A_, A_));
  HS_PETSC(KSPSetTolerances(gmres_, 1e-30, rtol * bn, PETSC_DEFAULT, 30));
  HS_PETSC(KSPSolve(gmres_, b, x));  // not converged in 30: the best it found (Newton judges)
  HS_PETSC(VecNorm(x, NORM_2, &rn));
  return std::isfinite(rn);
}

}  // namespace hypershape::solver
