#include "hypershape/solver/tangent.hpp"

#include <petscmat.h>

#include <algorithm>
#include <stdexcept>
#include <string>

#include "hypershape/core/error.hpp"
#include "log_events.hpp"

namespace hypershape::solver {

LinearCounters& LinearCounters::operator+=(const LinearCounters& o) {
  numeric_factorizations += o.numeric_factorizations;
  symbolic_factorizations += o.symbolic_factorizations;
  krylov_iterations += o.krylov_iterations;
  tangent_assemblies += o.tangent_assemblies;
  modified_solves += o.modified_solves;
  return *this;
}

LinearCounters LinearCounters::operator-(const LinearCounters& o) const {
  LinearCounters d = *this;
  d.numeric_factorizations -= o.numeric_factorizations;
  d.symbolic_factorizations -= o.symbolic_factorizations;
  d.krylov_iterations -= o.krylov_iterations;
  d.tangent_assemblies -= o.tangent_assemblies;
  d.modified_solves -= o.modified_solves;
  return d;
}

namespace {

/// Converged, or stopped at its iteration limit (then a factorisation of this tangent follows).
bool usable(KSPConvergedReason r) { return r > 0 || r == KSP_DIVERGED_ITS; }

}  // namespace

Tangent::Tangent(const physics::Problem& problem, const TangentOptions& opt, const std::string& prefix)
    : problem_(problem), opt_(opt), prefix_(prefix) {
  if (opt_.krylov_budget <= 0) opt_.krylov_budget = problem.space().dim() == 2 ? 25 : 60;
  forcing_ = opt_.krylov_rtol;
  J_ = problem.create_matrix();
  // A kept factor is the direct solver's: with factor reuse, auto means direct. A follower
  // load's tangent is not symmetric (CG and the stability check by LOBPCG need it so): direct.
  if (lu() && opt_.linear != LinearSolver::automatic && opt_.linear != LinearSolver::direct)
    throw std::invalid_argument("a follower load's tangent is not symmetric: the linear solver must be direct (LU)");
  linear_ = (opt_.reuse || lu()) && opt_.linear == LinearSolver::automatic
                ? LinearSolver::direct
                : resolve_linear_solver(opt_.linear, problem.space().dim(), problem.space().n_dofs_global(), opt_.auto_dofs);
  if (multigrid()) {
    if (opt_.reuse) throw std::logic_error("a kept factor (reuse) and a multigrid solver exclude each other");
    set_rigid_body_near_null_space(problem, J_);
    amg_ = make_multigrid_ksp(problem.comm(), linear_, prefix);
  }
  work_ = std::make_unique<LdltFactor>(problem, prefix, !lu(), opt_.single_factor);
  krylov_ = make_factor_preconditioned_gmres(problem.comm(), this, apply_shell, "kept LDL^T factor of an earlier tangent");
  HS_PETSC(KSPSetOptionsPrefix(krylov_, (prefix + "tangent_").c_str()));
  HS_PETSC(KSPGMRESSetRestart(krylov_, 40));
  HS_PETSC(KSPSetOperators(krylov_, J_, J_));
  HS_PETSC(KSPSetFromOptions(krylov_));
}

PetscErrorCode Tangent::apply_shell(PC pc, Vec x, Vec y) {
  void* ctx;
  PetscFunctionBeginUser;
  PetscCall(PCShellGetContext(pc, &ctx));
  auto* self = static_cast<Tangent*>(ctx);
  try {
    // A factor of an earlier tangent preconditions this one: a single-precision factor's solve is
    // not refined to its own matrix (2-3 more back-solves and products, for digits GMRES does not
    // need); a double factor's is its solve.
    if (!self->factor().precondition(x, y)) PetscCall(VecSet(y, PETSC_INFINITY));  // the Krylov solve then fails
  } catch (const std::exception& e) {
    SETERRQ(PETSC_COMM_SELF, PETSC_ERR_LIB, "%s", e.what());
  }
  PetscFunctionReturn(0);
}

bool Tangent::assemble(Vec u, double s) {
  LogEvent e(events().tangent_assembly);
  current_ = false;
  amg_current_ = false;
  symmetric_negative_ = -2;
  ++n_.tangent_assemblies;
  return problem_.jacobian(u, J_, s);
}

void Tangent::shift(double mu) {
  current_ = false;
  amg_current_ = false;
  symmetric_negative_ = -2;
  HS_PETSC(MatShift(J_, mu));
}

bool Tangent::factorise() {
  LogEvent e(events().factorisation);
  if (!work_->factored()) ++n_.symbolic_factorizations;  // the analysis, on the first only
  ++n_.numeric_factorizations;
  use_rest_ = false;
  since_factor_ = 0;
  current_ = work_->factorise(J_);
  return current_;
}

bool Tangent::use_rest_factor(Vec rest) {
  // In 3D only where the factors are single precision: two of them hold what one double did.
  if (lu() || (problem_.space().dim() != 2 && !work_->single())) return false;
  if (!rest_) {
    LogEvent e(events().factorisation);
    J0_ = problem_.create_matrix();
    ++n_.tangent_assemblies;
    if (!problem_.jacobian(rest, J0_)) return false;
    rest_ = std::make_unique<LdltFactor>(problem_, prefix_, true, opt_.single_factor);
    ++n_.symbolic_factorizations;
    ++n_.numeric_factorizations;  // once per problem
    if (!rest_->factorise(J0_)) {
      rest_.reset();
      return false;
    }
  }
  use_rest_ = true;
  current_ = false;
  since_factor_ = 0;
  return true;
}

bool Tangent::apply_factor(Vec x, Vec y, bool refined) {
  LogEvent e(events().factor_solve);
  return refined ? factor().solve(x, y) : factor().precondition(x, y);
}

int Tangent::negative_eigenvalues() {
  if (!lu()) return factor().negative_eigenvalues();
  return current_ ? symmetric_part_inertia() : -1;
}

int Tangent::symmetric_part_inertia() {
  if (symmetric_negative_ != -2) return symmetric_negative_;
  LogEvent e(events().stability);
  // S = (K + K^T)/2 on K's pattern (structurally symmetric: K^T has the same one).
  if (Kt_) {
    Mat kt = Kt_;
    HS_PETSC(MatTranspose(J_, MAT_REUSE_MATRIX, &kt));
  } else {
    HS_PETSC(MatTranspose(J_, MAT_INITIAL_MATRIX, Kt_.out()));
  }
  if (!S_) {
    HS_PETSC(MatDuplicate(J_, MAT_DO_NOT_COPY_VALUES, S_.out()));
    HS_PETSC(MatSetOption(S_, MAT_SYMMETRIC, PETSC_TRUE));
    HS_PETSC(MatSetOption(S_, MAT_SYMMETRY_ETERNAL, PETSC_TRUE));
    symmetric_part_ = std::make_unique<LdltFactor>(problem_, prefix_ + "stability_");
    ++n_.symbolic_factorizations;
  }
  HS_PETSC(MatCopy(J_, S_, SAME_NONZERO_PATTERN));
  HS_PETSC(MatAXPY(S_, 1.0, Kt_, SUBSET_NONZERO_PATTERN));
  HS_PETSC(MatScale(S_, 0.5));
  ++n_.numeric_factorizations;
  symmetric_negative_ = symmetric_part_->factorise(S_) ? symmetric_part_->negative_eigenvalues() : -1;
  return symmetric_negative_;
}

KSPConvergedReason Tangent::run_krylov(KSP ksp, Vec b, Vec x, bool guess, int max_its, PetscInt& its) {
  // Relative to ||b|| also with an initial guess (PETSc's default test would take the guess's
  // residual as the reference and ask far more of a good guess than of none).
  PetscReal bn;
  HS_PETSC(VecNorm(b, NORM_2, &bn));
  HS_PETSC(KSPSetTolerances(ksp, 1e-30, forcing_ * bn, PETSC_DEFAULT, std::max(max_its, 1)));
  HS_PETSC(KSPSetInitialGuessNonzero(ksp, guess ? PETSC_TRUE : PETSC_FALSE));
  HS_PETSC(KSPSolve(ksp, b, x));
  KSPConvergedReason r;
  HS_PETSC(KSPGetIterationNumber(ksp, &its));
  HS_PETSC(KSPGetConvergedReason(ksp, &r));
  n_.krylov_iterations += its;
  return r;
}

bool Tangent::krylov_solve(Vec b, Vec x, bool guess, int max_its, bool& converged) {
  LogEvent e(events().krylov);
  PetscInt its;
  const KSPConvergedReason r = run_krylov(krylov_, b, x, guess, max_its, its);
  since_factor_ += int(its);
  converged = r > 0;
  return usable(r);
}

void Tangent::set_up_multigrid() {
  if (amg_current_) return;
  LogEvent e(events().multigrid_setup);
  HS_PETSC(KSPSetOperators(amg_, J_, J_));
  HS_PETSC(KSPSetUp(amg_));
  amg_current_ = true;
}

bool Tangent::multigrid_solve(Vec b, Vec x, bool guess) {
  set_up_multigrid();
  LogEvent e(events().krylov);
  PetscInt its;
  const KSPConvergedReason r = run_krylov(amg_, b, x, guess, 1000, its);
  if (r > 0) return true;
  // CG stops on negative curvature (an indefinite tangent past a limit point) or stagnates:
  // this tangent is factorised instead, so the path goes on as the direct Newton's would.
  HS_PETSC(PetscInfo(amg_.get(), "multigrid solve failed (%s after %d its): factorising\n", KSPConvergedReasons[r], int(its)));
  if (!current_ && !factorise()) return false;
  return apply_factor(b, x);
}

int Tangent::stability(Vec start) {
  if (lu()) return symmetric_part_inertia();
  set_up_multigrid();
  LogEvent e(events().stability);
  PC pc;
  HS_PETSC(KSPGetPC(amg_, &pc));
  // One digit of the smallest eigenvalue settles its sign; 100 iterations of LOBPCG cost about
  // as much as two CG solves with the same AMG.
  const EigenEstimate est = smallest_eigenvalue(J_, pc, start, 0.1, 100);
  n_.krylov_iterations += est.iterations;
  HS_PETSC(PetscInfo(amg_.get(), "stability: smallest eigenvalue %g (residual %g, %d LOBPCG its)%s\n", est.value,
                     est.residual, est.iterations, est.settled ? "" : ": not settled, factorising"));
  if (est.settled) return est.value < 0 ? 1 : 0;
  if (!factorise()) return -1;
  return factor().negative_eigenvalues();
}

bool Tangent::solve_pair(Vec b1, Vec x1, bool guess1, Vec b2, Vec x2, bool absolute) {
  if (multigrid() || opt_.reuse) return solve(b1, x1, guess1) && solve(b2, x2, false);
  if (!current_ && !factorise()) return false;
  LogEvent e(events().factor_solve);
  if (absolute && factor().has_absolute()) ++n_.modified_solves;
  return factor().solve_pair(b1, x1, b2, x2, absolute);
}

bool Tangent::solve(Vec b, Vec x, bool guess) {
  if (multigrid()) return multigrid_solve(b, x, guess);
  if (!opt_.reuse) {  // a direct Newton: factorise every assembled tangent
    if (!current_ && !factorise()) return false;
    return apply_factor(b, x);
  }
  const int budget = opt_.krylov_budget;
  // Buy a factorisation once the rented (Krylov) work since the last one has cost as much.
  const bool have_factor = use_rest_ || work_->factored();
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
