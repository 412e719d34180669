/// Load control: Newton solves at a given load factor on the SNES (its Newton loop, converged
/// reason and -snes_monitor are PETSc's), adaptive load continuation, the linear response, and
/// the former alpha search (control: load) on top of them.
#include "hypershape/solver/nonlinear.hpp"

#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include "hypershape/core/error.hpp"
#include "hypershape/core/timer.hpp"
#include "log_events.hpp"

namespace hypershape::solver {

bool NonlinearSolver::newton(double s, SolveResult& r, double fixed_norm, double rtol) {
  s_eval_ = s;
  if (!user_atol_) {
    const double atol = opt_.atol + (rtol > 0 ? rtol : opt_.rtol) * (std::abs(s) * problem_.load_norm() + fixed_norm);
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
  LogEvent event(events().load_control);
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
    if (r.newton_iterations >= opt_.newton_budget) {
      r.reason = "Newton budget of " + std::to_string(opt_.newton_budget) + " iterations spent";
      break;
    }
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
  core::VecH du = problem_.create_vector();
  return linear_response(du).value_or(0.0);
}

std::optional<double> NonlinearSolver::linear_response(Vec du) {
  HS_PETSC(VecCopy(u_, backup_));
  ++snes_linear_.tangent_assemblies;
  if (!problem_.jacobian(u_, J_, s_)) return std::nullopt;
  ++snes_linear_.numeric_factorizations;
  KSP ksp;
  HS_PETSC(SNESGetKSP(snes_, &ksp));
  HS_PETSC(KSPSetOperators(ksp, J_, J_));
  HS_PETSC(KSPSolve(ksp, problem_.load_at(u_), du));
  return problem_.max_displacement(du);
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
    if (t.newton_iterations >= opt_.newton_budget) {
      t.reason = "Newton budget of " + std::to_string(opt_.newton_budget) + " iterations spent";
      return t;
    }
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
