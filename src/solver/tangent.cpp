#include "hypershape/solver/tangent.hpp"

#include <petscmat.h>

#include <algorithm>
#include <string>

#include "hypershape/core/error.hpp"
#include "log_events.hpp"

namespace hypershape::solver {

LinearCounters& LinearCounters::operator+=(const LinearCounters& o) {
  numeric_factorizations += o.numeric_factorizations;
  symbolic_factorizations += o.symbolic_factorizations;
  krylov_iterations += o.krylov_iterations;
  tangent_assemblies += o.tangent_assemblies;
  return *this;
}

LinearCounters LinearCounters::operator-(const LinearCounters& o) const {
  LinearCounters d = *this;
  d.numeric_factorizations -= o.numeric_factorizations;
  d.symbolic_factorizations -= o.symbolic_factorizations;
  d.krylov_iterations -= o.krylov_iterations;
  d.tangent_assemblies -= o.tangent_assemblies;
  return d;
}

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
  PetscInt neg = -1, zero, pos;
  if (p == MATSOLVERMUMPS) {
    HS_PETSC(MatMumpsGetInfog(F, 12, &neg));
  } else if (p == MATSOLVERPETSC) {
    HS_PETSC(MatGetInertia(F, &neg, &zero, &pos));
  }
  return int(neg);
}

void configure_direct_solver(KSP ksp, MPI_Comm comm, int dim) {
  PC pc;
  HS_PETSC(KSPSetType(ksp, KSPPREONLY));
  HS_PETSC(KSPGetPC(ksp, &pc));
  HS_PETSC(PCSetType(pc, PCCHOLESKY));
  // 2D on one rank: PETSc's own sparse Cholesky (LDL^T without pivoting) in the quotient
  // minimum degree ordering; measured 1.4x faster per load case than MUMPS on Random2D shapes,
  // whose per-call overhead dominates at a few thousand unknowns. In 3D its non-supernodal
  // factorisation is far slower than MUMPS (a Random3D load case took minutes), and a solver
  // group of several ranks needs a parallel one: MUMPS. Both report the inertia.
  PetscMPIInt ranks;
  MPI_Comm_size(comm, &ranks);
  if (ranks == 1 && dim == 2) {
    HS_PETSC(PCFactorSetMatSolverType(pc, MATSOLVERPETSC));
    HS_PETSC(PCFactorSetMatOrderingType(pc, MATORDERINGQMD));
  } else {
    HS_PETSC(PCFactorSetMatSolverType(pc, MATSOLVERMUMPS));
  }
}

namespace {

core::KSPH make_factor_ksp(const physics::Problem& p, const std::string& prefix, Mat A) {
  core::KSPH ksp;
  HS_PETSC(KSPCreate(p.comm(), ksp.out()));
  if (!prefix.empty()) HS_PETSC(KSPSetOptionsPrefix(ksp, prefix.c_str()));
  configure_direct_solver(ksp, p.comm(), p.space().dim());
  HS_PETSC(KSPSetFromOptions(ksp));
  HS_PETSC(KSPSetOperators(ksp, A, A));
  return ksp;
}

bool solved(KSP ksp) {
  KSPConvergedReason r;
  HS_PETSC(KSPGetConvergedReason(ksp, &r));
  return r > 0;
}

}  // namespace

Tangent::Tangent(const physics::Problem& problem, const TangentOptions& opt, const std::string& prefix)
    : problem_(problem), opt_(opt) {
  if (opt_.krylov_budget <= 0) opt_.krylov_budget = problem.space().dim() == 2 ? 25 : 60;
  forcing_ = opt_.krylov_rtol;
  J_ = problem.create_matrix();
  F_ = problem.create_matrix();
  work_ksp_ = make_factor_ksp(problem, prefix, F_);
  HS_PETSC(KSPCreate(problem.comm(), krylov_.out()));
  HS_PETSC(KSPSetOptionsPrefix(krylov_, (prefix + "tangent_").c_str()));
  HS_PETSC(KSPSetType(krylov_, KSPGMRES));
  HS_PETSC(KSPGMRESSetRestart(krylov_, 40));
  // Right preconditioning: the convergence test sees the true residual of K x = b.
  HS_PETSC(KSPSetPCSide(krylov_, PC_RIGHT));
  PC pc;
  HS_PETSC(KSPGetPC(krylov_, &pc));
  HS_PETSC(PCSetType(pc, PCSHELL));
  HS_PETSC(PCShellSetContext(pc, this));
  HS_PETSC(PCShellSetApply(pc, apply_shell));
  HS_PETSC(PCShellSetName(pc, "kept LDL^T factor of an earlier tangent"));
  HS_PETSC(KSPSetOperators(krylov_, J_, J_));
  HS_PETSC(KSPSetFromOptions(krylov_));
}

PetscErrorCode Tangent::apply_shell(PC pc, Vec x, Vec y) {
  void* ctx;
  PetscFunctionBeginUser;
  PetscCall(PCShellGetContext(pc, &ctx));
  auto* self = static_cast<Tangent*>(ctx);
  PetscCall(KSPSolve(self->factor_ksp(), x, y));
  PetscFunctionReturn(0);
}

bool Tangent::assemble(Vec u) {
  LogEvent e(events().tangent_assembly);
  current_ = false;
  ++n_.tangent_assemblies;
  return problem_.jacobian(u, J_);
}

void Tangent::shift(double mu) {
  current_ = false;
  HS_PETSC(MatShift(J_, mu));
}

bool Tangent::factorise() {
  LogEvent e(events().factorisation);
  HS_PETSC(MatCopy(J_, F_, SAME_NONZERO_PATTERN));
  if (!work_factored_) ++n_.symbolic_factorizations;
  ++n_.numeric_factorizations;
  work_factored_ = true;
  use_rest_ = false;
  since_factor_ = 0;
  // KSPSetOperators marks the new values; PCSetUp factorises now (not at the first solve), so
  // that a failed factorisation is seen here and the event times it.
  PC pc;
  PCFailedReason why;
  HS_PETSC(KSPSetOperators(work_ksp_, F_, F_));
  HS_PETSC(KSPGetPC(work_ksp_, &pc));
  HS_PETSC(PCSetUp(pc));
  HS_PETSC(PCGetFailedReason(pc, &why));
  current_ = why == PC_NOERROR;
  return current_;
}

bool Tangent::use_rest_factor(Vec rest) {
  if (problem_.space().dim() != 2) return false;
  if (!rest_ksp_) {
    LogEvent e(events().factorisation);
    F0_ = problem_.create_matrix();
    ++n_.tangent_assemblies;
    if (!problem_.jacobian(rest, F0_)) return false;
    rest_ksp_ = make_factor_ksp(problem_, [&] {
      const char* p = nullptr;
      HS_PETSC(KSPGetOptionsPrefix(work_ksp_, &p));
      return std::string(p ? p : "");
    }(), F0_);
    PC pc;
    HS_PETSC(KSPGetPC(rest_ksp_, &pc));
    HS_PETSC(PCSetUp(pc));
    ++n_.symbolic_factorizations;
    ++n_.numeric_factorizations;  // once per problem
  }
  use_rest_ = true;
  current_ = false;
  since_factor_ = 0;
  return true;
}

bool Tangent::apply_factor(Vec x, Vec y) {
  LogEvent e(events().factor_solve);
  KSP ksp = factor_ksp();
  HS_PETSC(KSPSolve(ksp, x, y));
  return solved(ksp);
}

int Tangent::negative_eigenvalues() const {
  if (!use_rest_ && !work_factored_) return -1;
  return solver::negative_eigenvalues(factor_ksp());
}

bool Tangent::krylov_solve(Vec b, Vec x, bool guess, int max_its, bool& converged) {
  LogEvent e(events().krylov);
  // Relative to ||b|| also with an initial guess (PETSc's default test would take the guess's
  // residual as the reference and ask far more of a good guess than of none).
  PetscReal bn;
  HS_PETSC(VecNorm(b, NORM_2, &bn));
  HS_PETSC(KSPSetTolerances(krylov_, 1e-30, forcing_ * bn, PETSC_DEFAULT, std::max(max_its, 1)));
  HS_PETSC(KSPSetInitialGuessNonzero(krylov_, guess ? PETSC_TRUE : PETSC_FALSE));
  HS_PETSC(KSPSolve(krylov_, b, x));
  PetscInt its;
  KSPConvergedReason r;
  HS_PETSC(KSPGetIterationNumber(krylov_, &its));
  HS_PETSC(KSPGetConvergedReason(krylov_, &r));
  n_.krylov_iterations += its;
  since_factor_ += int(its);
  converged = r > 0;
  return r > 0 || r == KSP_DIVERGED_ITS;
}

bool Tangent::solve(Vec b, Vec x, bool guess) {
  if (!opt_.reuse) {  // the former direct Newton: factorise every assembled tangent
    if (!current_ && !factorise()) return false;
    return apply_factor(b, x);
  }
  const int budget = opt_.krylov_budget;
  // Buy a factorisation once the rented (Krylov) work since the last one has cost as much.
  const bool have_factor = use_rest_ || work_factored_;
  if (!current_ && (since_factor_ >= budget || !have_factor) && !factorise()) return false;
  bool converged = false;
  krylov_solve(b, x, guess, std::max(budget - since_factor_, 4), converged);
  if (converged) return true;
  if (current_) return false;  // not even with the factor of this very tangent
  if (!factorise()) return false;
  krylov_solve(b, x, false, budget, converged);
  return converged;
}

}  // namespace hypershape::solver
