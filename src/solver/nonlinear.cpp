#include "hypershape/solver/nonlinear.hpp"

#include "hypershape/core/timer.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "hypershape/core/error.hpp"
#include "hypershape/core/log.hpp"

namespace hypershape::solver {

namespace {

/// C++ exceptions must not unwind through PETSc frames: turn them into PETSc errors.
template <class F>
PetscErrorCode guarded(F&& f) {
  try {
    f();
    return 0;
  } catch (const std::exception& e) {
    return PetscError(PETSC_COMM_SELF, __LINE__, "hypershape callback", __FILE__, PETSC_ERR_LIB,
                      PETSC_ERROR_INITIAL, "%s", e.what());
  }
}

}  // namespace

void set_default_options(const std::vector<std::pair<std::string, std::string>>& options) {
  for (const auto& [k, v] : options) {
    PetscBool set;
    HS_PETSC(PetscOptionsHasName(nullptr, nullptr, k.c_str(), &set));
    if (!set) HS_PETSC(PetscOptionsSetValue(nullptr, k.c_str(), v.empty() ? nullptr : v.c_str()));
  }
}

NonlinearSolver::NonlinearSolver(const physics::Problem& problem, const SolverOptions& opt,
                                 const std::string& prefix)
    : problem_(problem), opt_(opt) {
  MPI_Comm comm = problem.comm();
  J_ = problem.create_matrix();
  u_ = problem.create_vector();
  backup_ = problem.create_vector();
  r_ = problem.create_vector();
  HS_PETSC(SNESCreate(comm, snes_.out()));
  if (!prefix.empty()) HS_PETSC(SNESSetOptionsPrefix(snes_, prefix.c_str()));
  // No SNESSetDM: SNES callbacks live on the DM's DMSNES, so solvers sharing the problem's DM
  // would overwrite each other's context. We assemble ourselves; SNES keeps a private shell DM.
  HS_PETSC(SNESSetFunction(snes_, r_, form_function, this));
  HS_PETSC(SNESSetJacobian(snes_, J_, J_, form_jacobian, this));
  HS_PETSC(SNESSetType(snes_, SNESNEWTONLS));
  SNESLineSearch ls;
  HS_PETSC(SNESGetLineSearch(snes_, &ls));
  if (opt.guard) {
    HS_PETSC(SNESSetObjective(snes_, form_objective, this));
    HS_PETSC(SNESLineSearchSetType(ls, SNESLINESEARCHSHELL));
    HS_PETSC(SNESLineSearchShellSetUserFunc(ls, guarded_line_search, this));
  } else {
    HS_PETSC(SNESLineSearchSetType(ls, SNESLINESEARCHBASIC));
  }
  HS_PETSC(SNESSetTolerances(snes_, opt.atol, 1e-50, 0.0, opt.max_newton, -1));
  KSP ksp;
  PC pc;
  HS_PETSC(SNESGetKSP(snes_, &ksp));
  HS_PETSC(KSPSetType(ksp, KSPPREONLY));
  HS_PETSC(KSPGetPC(ksp, &pc));
  HS_PETSC(PCSetType(pc, PCCHOLESKY));
  HS_PETSC(PCFactorSetMatSolverType(pc, MATSOLVERMUMPS));
  HS_PETSC(SNESSetFromOptions(snes_));
  PetscBool has_atol = PETSC_FALSE;
  HS_PETSC(PetscOptionsHasName(nullptr, prefix.empty() ? nullptr : prefix.c_str(), "-snes_atol",
                               &has_atol));
  user_atol_ = has_atol;
}

void NonlinearSolver::reset() {
  HS_PETSC(VecZeroEntries(u_));
  s_ = 0;
}

PetscErrorCode NonlinearSolver::form_function(SNES snes, Vec x, Vec f, void* ctx) {
  auto* self = static_cast<NonlinearSolver*>(ctx);
  return guarded([&] {
    if (!self->problem_.residual(x, self->s_eval_, f)) HS_PETSC(SNESSetFunctionDomainError(snes));
  });
}

PetscErrorCode NonlinearSolver::form_jacobian(SNES snes, Vec x, Mat, Mat P, void* ctx) {
  auto* self = static_cast<NonlinearSolver*>(ctx);
  return guarded([&] {
    if (!self->problem_.jacobian(x, P)) HS_PETSC(SNESSetJacobianDomainError(snes));
  });
}

PetscErrorCode NonlinearSolver::form_objective(SNES, Vec x, PetscReal* obj, void* ctx) {
  auto* self = static_cast<NonlinearSolver*>(ctx);
  return guarded([&] {
    double e;
    self->problem_.energy(x, self->s_eval_, e);
    *obj = e;  // +inf when some det F <= 0
  });
}

PetscErrorCode NonlinearSolver::guarded_line_search(SNESLineSearch ls, void* ctx) {
  auto* self = static_cast<NonlinearSolver*>(ctx);
  return guarded([&] { self->line_search(ls); });
}

void NonlinearSolver::line_search(SNESLineSearch ls) {
  // Newton step: W = X - lambda Y. Backtrack from lambda = 1 until W is admissible (det F > 0
  // everywhere: finite energy) and either the energy decreases (Armijo) or, where the tangent
  // is not positive definite or the energy change is below round-off, the residual norm does.
  Vec X, F, Y, W, G;
  HS_PETSC(SNESLineSearchGetVecs(ls, &X, &F, &Y, &W, &G));
  PetscReal fnorm0, slope;
  HS_PETSC(VecNorm(F, NORM_2, &fnorm0));
  HS_PETSC(VecDot(F, Y, &slope));
  slope = -slope;  // d/dlambda of the energy at lambda = 0
  double e0;
  problem_.energy(X, s_eval_, e0);
  constexpr double c = 1e-4;
  double lambda = 1.0;
  bool accepted = false;
  for (int it = 0; it < 40 && lambda > 1e-10; ++it) {
    HS_PETSC(VecWAXPY(W, -lambda, Y, X));
    double e;
    if (!problem_.energy(W, s_eval_, e)) {  // inadmissible: never accept, halve
      lambda *= 0.5;
      continue;
    }
    if (slope < 0 && e <= e0 + c * lambda * slope) {
      accepted = true;
      break;
    }
    const bool ok = problem_.residual(W, s_eval_, G);
    PetscReal gnorm;
    HS_PETSC(VecNorm(G, NORM_2, &gnorm));
    if (ok && gnorm <= (1.0 - c * lambda) * fnorm0) {
      accepted = true;
      break;
    }
    if (slope < 0 && std::isfinite(e)) {  // quadratic model of the energy along the step
      const double denom = 2.0 * (e - e0 - slope * lambda);
      const double l = denom > 0 ? -slope * lambda * lambda / denom : 0.5 * lambda;
      lambda = std::clamp(l, 0.1 * lambda, 0.5 * lambda);
    } else {
      lambda *= 0.5;
    }
  }
  if (!accepted) {
    HS_PETSC(SNESLineSearchSetReason(ls, SNES_LINESEARCH_FAILED_REDUCT));
    return;
  }
  if (!problem_.residual(W, s_eval_, G)) {
    HS_PETSC(SNESLineSearchSetReason(ls, SNES_LINESEARCH_FAILED_DOMAIN));
    return;
  }
  HS_PETSC(VecCopy(W, X));
  HS_PETSC(VecCopy(G, F));
  HS_PETSC(SNESLineSearchSetLambda(ls, lambda));
  HS_PETSC(SNESLineSearchComputeNorms(ls));
  HS_PETSC(SNESLineSearchSetReason(ls, SNES_LINESEARCH_SUCCEEDED));
}

bool NonlinearSolver::newton(double s, SolveResult& r) {
  s_eval_ = s;
  if (!user_atol_) {
    const double atol = opt_.atol + opt_.rtol * std::abs(s) * problem_.load_norm();
    HS_PETSC(SNESSetTolerances(snes_, atol, PETSC_DEFAULT, PETSC_DEFAULT, PETSC_DEFAULT, PETSC_DEFAULT));
  }
  HS_PETSC(SNESSolve(snes_, nullptr, u_));
  SNESConvergedReason reason;
  PetscInt its, lits;
  HS_PETSC(SNESGetConvergedReason(snes_, &reason));
  HS_PETSC(SNESGetIterationNumber(snes_, &its));
  HS_PETSC(SNESGetLinearSolveIterations(snes_, &lits));
  r.newton_iterations += int(its);
  r.linear_solves += int(lits);
  r.reason = SNESConvergedReasons[reason];
  // Check the true residual ourselves: a small step is not a small residual.
  bool ok = reason > 0 && reason != SNES_CONVERGED_SNORM_RELATIVE;
  if (reason > 0) {
    ok = ok && problem_.residual(u_, s, r_);
    PetscReal fn;
    HS_PETSC(VecNorm(r_, NORM_2, &fn));
    r.residual_norm = fn;
    PetscReal atol, rtol, stol;
    PetscInt maxit, maxf;
    HS_PETSC(SNESGetTolerances(snes_, &atol, &rtol, &stol, &maxit, &maxf));
    ok = ok && std::isfinite(fn);
    if (reason == SNES_CONVERGED_SNORM_RELATIVE) r.reason = "step small, residual not";
  }
  return ok;
}

SolveResult NonlinearSolver::solve(double target) {
  SolveResult r;
  const double total = target - s_;
  if (total == 0.0) {
    r.converged = true;
    r.reason = "already at this load";
    r.load_factor = s_;
    r.max_displacement = problem_.max_displacement(u_);
    return r;
  }
  double step = total;
  const double min_step = std::abs(total) * opt_.min_increment;
  int attempts = 0;
  while (s_ != target) {
    if (++attempts > opt_.max_increments) {
      r.reason = "too many load increments (last: " + r.reason + ")";
      break;
    }
    const double s_try = (std::abs(target - s_) <= std::abs(step) * (1 + 1e-12)) ? target : s_ + step;
    // No explicit predictor: Newton's first step from the converged state is the tangent one.
    HS_PETSC(VecCopy(u_, backup_));
    if (newton(s_try, r)) {
      s_ = s_try;
      ++r.increments;
      step *= 2.0;
    } else {
      HS_PETSC(VecCopy(backup_, u_));
      ++r.failed_increments;
      step = 0.5 * (s_try - s_);
      if (std::abs(step) < min_step) {
        r.reason = "load increment below minimum (last: " + r.reason + ")";
        break;
      }
    }
  }
  r.converged = s_ == target;
  if (r.converged && r.failed_increments == 0 && r.increments == 1) { /* full step */ }
  r.load_factor = s_;
  r.max_displacement = problem_.max_displacement(u_);
  return r;
}

double NonlinearSolver::linear_response() {
  HS_PETSC(VecCopy(u_, backup_));
  if (!problem_.jacobian(u_, J_)) return 0.0;
  KSP ksp;
  HS_PETSC(SNESGetKSP(snes_, &ksp));
  HS_PETSC(KSPSetOperators(ksp, J_, J_));
  core::VecH du = problem_.create_vector();
  HS_PETSC(KSPSolve(ksp, problem_.load(), du));
  return problem_.max_displacement(du);
}

TargetResult NonlinearSolver::solve_for_target(double target) {
  const double start = core::now_seconds();
  TargetResult t = search_target(target, start);
  t.seconds_total = core::now_seconds() - start;
  if (t.solves <= 1) t.seconds_first_solve = t.seconds_total;
  return t;
}

TargetResult NonlinearSolver::search_target(double target, double start) {
  TargetResult t;
  auto account = [&](const SolveResult& r) {
    if (t.solves == 0) t.seconds_first_solve = core::now_seconds() - start;
    ++t.solves;
    t.newton_iterations += r.newton_iterations;
    t.failed_increments += r.failed_increments;
  };
  // First guess from the linear response at the current state.
  double alpha;
  const double m_now = problem_.max_displacement(u_);
  if (s_ == 0.0 || m_now == 0.0) {
    const double m1 = linear_response();
    if (!(m1 > 0) || !std::isfinite(m1)) {
      t.reason = "no displacement under the nominal load";
      return t;
    }
    alpha = target / m1;
  } else {
    alpha = s_ * target / m_now;
  }
  double lo = 0, hi = INFINITY;  // bracket in alpha: m(lo) < target < m(hi)
  std::vector<std::pair<double, double>> hist;  // (log alpha, log m)
  for (int k = 0; k < opt_.max_target_solves; ++k) {
    SolveResult r = solve(alpha);
    account(r);
    if (!r.converged) {
      // Could not reach this alpha: it is too large (or a step failed); search below it.
      hi = std::min(hi, alpha);
      t.reason = r.reason;
      alpha = lo > 0 ? std::sqrt(lo * alpha) : 0.5 * (s_ > 0 ? s_ + alpha : alpha);
      continue;
    }
    const double m = r.max_displacement;
    t.alpha = alpha;
    t.max_displacement = m;
    if (std::abs(m / target - 1.0) <= opt_.target_rtol) {
      t.converged = true;
      t.reason = "target reached";
      return t;
    }
    if (m < target) lo = std::max(lo, alpha); else hi = std::min(hi, alpha);
    hist.emplace_back(std::log(alpha), std::log(m));
    double slope = 1.0;
    if (hist.size() >= 2) {
      auto [a1, m1] = hist[hist.size() - 1];
      auto [a0, m0] = hist[hist.size() - 2];
      if (std::abs(a1 - a0) > 1e-14) slope = std::clamp((m1 - m0) / (a1 - a0), 0.05, 20.0);
    }
    double next = std::exp(std::log(alpha) + (std::log(target) - std::log(m)) / slope);
    if (!(next > lo && next < hi)) next = std::isfinite(hi) && lo > 0 ? std::sqrt(lo * hi)
                                       : (m < target ? 2 * alpha : 0.5 * alpha);
    alpha = next;
  }
  if (t.reason.empty() || t.reason == "target reached") t.reason = "alpha search did not converge";
  return t;
}

}  // namespace hypershape::solver
