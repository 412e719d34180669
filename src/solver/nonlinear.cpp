#include "hypershape/solver/nonlinear.hpp"

#include "hypershape/core/timer.hpp"
#include "hypershape/core/vec_array.hpp"
#include <petscmat.h>

#include <algorithm>
#include <utility>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "hypershape/core/error.hpp"
#include "hypershape/core/log.hpp"
#include "log_events.hpp"

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
  for (core::VecH* v : {&a_, &a0_, &b_, &c_, &du_, &w_, &v_, &v0_, &arc_dir_, &arc_prev_dir_}) *v = problem.create_vector();
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
  HS_PETSC(SNESGetKSP(snes_, &ksp));
  configure_direct_solver(ksp, problem.comm(), problem.space().dim(), problem.conservative());
  HS_PETSC(SNESSetFromOptions(snes_));
  const char* ksp_prefix = nullptr;
  HS_PETSC(KSPGetOptionsPrefix(ksp, &ksp_prefix));
  tangent_ = std::make_unique<Tangent>(problem, opt.tangent, ksp_prefix ? ksp_prefix : "");
  PetscBool has_atol = PETSC_FALSE;
  HS_PETSC(PetscOptionsHasName(nullptr, prefix.empty() ? nullptr : prefix.c_str(), "-snes_atol",
                               &has_atol));
  user_atol_ = has_atol;
}

void NonlinearSolver::reset() {
  HS_PETSC(VecZeroEntries(u_));
  s_ = 0;
  forget_evaluations();
}

void NonlinearSolver::forget_evaluations() {
  known_internal_ = NAN;
  ahead_internal_ = NAN;
}

PetscErrorCode NonlinearSolver::form_function(SNES snes, Vec x, Vec f, void* ctx) {
  auto* self = static_cast<NonlinearSolver*>(ctx);
  return guarded([&] {
    // From the kept internal force where x is the state it belongs to (the final check of a path).
    if (!self->residual_at(x, self->s_eval_, f)) HS_PETSC(SNESSetFunctionDomainError(snes));
  });
}

PetscErrorCode NonlinearSolver::form_jacobian(SNES snes, Vec x, Mat, Mat P, void* ctx) {
  auto* self = static_cast<NonlinearSolver*>(ctx);
  return guarded([&] {
    ++self->snes_linear_.tangent_assemblies;
    if (!self->problem_.jacobian(x, P, self->s_eval_)) HS_PETSC(SNESSetJacobianDomainError(snes));
    else ++self->snes_linear_.numeric_factorizations;  // the SNES's KSP factorises it next
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
  Vec X, F, Y, W, G;
  HS_PETSC(SNESLineSearchGetVecs(ls, &X, &F, &Y, &W, &G));
  const double lambda = backtrack(X, Y, F, s_eval_, W, G);
  if (lambda == 0.0) {
    HS_PETSC(SNESLineSearchSetReason(ls, SNES_LINESEARCH_FAILED_REDUCT));
    return;
  }
  accept_trial(W, X);
  HS_PETSC(VecCopy(G, F));
  HS_PETSC(SNESLineSearchSetLambda(ls, lambda));
  HS_PETSC(SNESLineSearchComputeNorms(ls));
  HS_PETSC(SNESLineSearchSetReason(ls, SNES_LINESEARCH_SUCCEEDED));
}

double NonlinearSolver::backtrack(Vec X, Vec Y, Vec F, double s, Vec W, Vec G) {
  // Newton step: W = X - lambda Y. Backtrack from lambda = 1 until W is admissible (det F > 0
  // everywhere: finite energy) and either the energy decreases (Armijo) or, where the tangent
  // is not positive definite or the energy change is below round-off, the residual norm does.
  // (With a follower load there is no energy: Problem::energy_along, whose slope is the same.)
  PetscReal fnorm0, slope;
  HS_PETSC(VecNorm(F, NORM_2, &fnorm0));
  HS_PETSC(VecDot(F, Y, &slope));
  slope = -slope;  // d/dlambda of the energy at lambda = 0
  const double e0 = energy_at_start(X, s);
  constexpr double c = 1e-4;
  double lambda = 1.0;
  for (int it = 0; it < 40 && lambda > 1e-10; ++it) {
    HS_PETSC(VecWAXPY(W, -lambda, Y, X));
    double e;
    trial_internal_ = NAN;
    if (!trial_force_) HS_PETSC(VecDuplicate(W, trial_force_.out()));
    const bool admissible = problem_.conservative() ? evaluate_trial(W, s, e, G) : problem_.energy_along(X, W, s, e);
    if (!admissible) {  // inadmissible: never accept, halve
      lambda *= 0.5;
      continue;
    }
    const bool ok = problem_.conservative() || problem_.residual(W, s, G);
    if (ok && slope < 0 && e <= e0 + c * lambda * slope) return lambda;
    PetscReal gnorm;
    HS_PETSC(VecNorm(G, NORM_2, &gnorm));
    if (ok && gnorm <= (1.0 - c * lambda) * fnorm0) return lambda;
    if (slope < 0 && std::isfinite(e)) {  // quadratic model of the energy along the step
      const double denom = 2.0 * (e - e0 - slope * lambda);
      const double l = denom > 0 ? -slope * lambda * lambda / denom : 0.5 * lambda;
      lambda = std::clamp(l, 0.1 * lambda, 0.5 * lambda);
    } else {
      lambda *= 0.5;
    }
  }
  return 0.0;
}

void NonlinearSolver::accept_trial(Vec W, Vec X) {
  HS_PETSC(VecCopy(W, X));
  keep_trial_as(X);
}

void NonlinearSolver::keep_trial_as(Vec X) {
  known_internal_ = trial_internal_;
  if (std::isnan(known_internal_)) return;
  if (!known_state_) HS_PETSC(VecDuplicate(X, known_state_.out()));
  HS_PETSC(VecCopy(X, known_state_));
  std::swap(known_force_, trial_force_);  // trial_force_ holds X's (the trial evaluated last)
}

bool NonlinearSolver::is_known_state(Vec X) {
  PetscBool same = PETSC_FALSE;
  if (!std::isnan(known_internal_)) HS_PETSC(VecEqual(X, known_state_, &same));
  return same;
}

double NonlinearSolver::energy_at_start(Vec X, double s) {
  if (is_known_state(X)) return problem_.energy_from_internal(X, s, known_internal_);
  double e;
  problem_.energy(X, s, e);
  return e;
}

bool NonlinearSolver::evaluate_known(Vec X, double s, Vec r) {
  // The numbers of residual() and energy(): one pass gives both bit for bit (unit.physics.assembly,
  // "Energy and residual in one pass equal the two passes bit for bit").
  if (!trial_force_) HS_PETSC(VecDuplicate(X, trial_force_.out()));
  double e;
  trial_internal_ = NAN;
  if (!problem_.energy_residual(X, s, e, r, &trial_internal_, trial_force_)) return false;
  keep_trial_as(X);
  return true;
}

bool NonlinearSolver::evaluate_ahead(Vec X, double s, Vec r) {
  ahead_internal_ = NAN;
  if (!problem_.conservative()) return problem_.residual(X, s, r);
  if (!ahead_force_) HS_PETSC(VecDuplicate(X, ahead_force_.out()));
  if (!ahead_state_) HS_PETSC(VecDuplicate(X, ahead_state_.out()));
  double e, internal;
  if (!problem_.energy_residual(X, s, e, r, &internal, ahead_force_)) return false;
  HS_PETSC(VecCopy(X, ahead_state_));
  ahead_internal_ = internal;
  return true;
}

bool NonlinearSolver::evaluate_trial(Vec W, double s, double& e, Vec G) {
  PetscBool same = PETSC_FALSE;
  if (!std::isnan(ahead_internal_)) HS_PETSC(VecEqual(W, ahead_state_, &same));
  if (!same) return problem_.energy_residual(W, s, e, G, &trial_internal_, trial_force_);
  // The numbers energy_residual gives: the energy and force are the same pass's.
  trial_internal_ = ahead_internal_;
  ahead_internal_ = NAN;
  std::swap(trial_force_, ahead_force_);
  e = problem_.energy_from_internal(W, s, trial_internal_);
  problem_.residual_from_internal(trial_force_, s, G);
  return true;
}

bool NonlinearSolver::residual_at(Vec X, double s, Vec r) {
  if (!is_known_state(X)) return problem_.residual(X, s, r);
  problem_.residual_from_internal(known_force_, s, r);
  return true;
}

bool verified_fold(const std::string& reason) { return reason.rfind("fold:", 0) == 0; }

TargetResult NonlinearSolver::timed(TargetResult t, double start, const LinearCounters& linear_before) const {
  t.seconds_total = core::now_seconds() - start;
  if (t.solves <= 1) t.seconds_first_solve = t.seconds_total;
  t.linear = linear_counters() - linear_before;
  return t;
}

TargetResult NonlinearSolver::solve_for_target(double target) {
  const double start = core::now_seconds();
  const LinearCounters linear_before = linear_counters();
  const double hint = step_hint_;
  TargetResult t = attempt_target(target, start);
  if (!t.converged && opt_.retry_from_rest && hint > 0 && opt_.control == Control::displacement && target > 0 &&
      !verified_fold(t.reason)) {
    // The hint (the previous load case's first increment) set this path's first increment, and
    // with it which branch a bifurcation on the way sent it to. From rest without it, as alone.
    // (Not after a verified fold: the path from rest reaches the same one; measured on the six
    // folds of the ten unseen-seed slices, each alone.)
    const double kept = step_hint_;
    const TargetResult first = t;
    reset();
    step_hint_ = 0;
    t = attempt_target(target, start);
    t.add_earlier(first, true);
    t.reason = t.converged ? "target reached from rest without the first-increment hint (first try: " +
                                 first.reason.substr(0, 400) + ")"
                           : first.reason.substr(0, 400) + "; from rest without the first-increment hint: " +
                                 t.reason.substr(0, 400);
    step_hint_ = kept;  // the next load case's hint as the first try left it
  }
  return timed(t, start, linear_before);
}

TargetResult NonlinearSolver::solve_for_target_from(Vec u, double load_factor, double target) {
  const double start = core::now_seconds();
  const LinearCounters linear_before = linear_counters();
  const double kept = step_hint_;
  HS_PETSC(VecCopy(u, u_));
  s_ = load_factor;
  TargetResult t = attempt_target(target, start);
  step_hint_ = kept;
  return timed(t, start, linear_before);
}

TargetResult NonlinearSolver::attempt_target(double target, double start) {
  forget_evaluations();  // the problem may have changed since (effects switched, a new load)
  TargetResult t = opt_.control == Control::displacement ? follow_path(target, start)
                                                          : search_target(target, start);
  // (t.solves == 0: the path never started, e.g. no tangent at the initial state: no branch.)
  const std::string first = t.reason;
  int switches = 0;
  for (; switches < opt_.branch_switches && opt_.control == Control::displacement && !t.converged &&
         target > 0 && t.solves > 0 && t.newton_iterations < opt_.newton_budget && problem_.conservative();
       ++switches)
    switch_branch(target, start, switches, t);
  // A fold verified on the path from rest (follow_path) stays the reason where no switch found
  // a stable state on another branch: the switches' own outcome follows it.
  if (!t.converged && switches > 0 && verified_fold(first))
    t.reason = first + "; " + std::to_string(switches) + " branch switch(es) found no stable state on target (last: " +
               t.reason.substr(0, 400) + ")";
  if (!t.converged && !problem_.conservative() && opt_.branch_switches > 0 && opt_.control == Control::displacement)
    t.reason += "; no branch switch: a follower load has no energy to minimise";
  if (opt_.arc_length_rescue && problem_.space().dim() == 2 && opt_.control == Control::displacement && !t.converged &&
      target > 0 && t.solves > 0 && problem_.conservative() && !problem_.has_fixed_load() &&
      !verified_fold(first)) {
    const TargetResult before = t;
    t = arc_path(target, start);
    t.add_earlier(before, true);
    t.reason = t.converged ? "target reached by arc-length continuation (before: " + before.reason.substr(0, 400) + ")"
                           : before.reason.substr(0, 400) + "; arc-length continuation: " + t.reason;
  }
  if (opt_.control == Control::displacement && !t.converged && opt_.fallback && target > 0) {
    // Fallback, measured on Random2D draws: where the path cannot be followed (Newton stalls
    // next to a bifurcation), load-controlled solves from the last converged state of the
    // path may still reach a stable equilibrium at the target (a buckled one).
    const TargetResult path = t;
    t = search_target(target, start);
    t.add_earlier(path, true);
    t.reason = (t.converged ? "target reached by load control" : t.reason) +
               " (displacement control: " + path.reason + ")";
  }
  return t;
}

LinearCounters NonlinearSolver::linear_counters() const {
  LinearCounters n = tangent_->counters();
  n += snes_linear_;
  // The SNES's KSP analyses its pattern once, on its first factorisation.
  if (snes_linear_.numeric_factorizations > 0) ++n.symbolic_factorizations;
  return n;
}

bool NonlinearSolver::apply_tangent_factor(Vec x, Vec y, bool refined) {
  return !tangent_->multigrid() && tangent_->has_factor() && tangent_->apply_factor(x, y, refined);
}

bool NonlinearSolver::rest_response() {
  if (!tangent_->use_rest_factor(u_)) return tangent_response(false);
  negative_pivots_ = -1;
  if (!tangent_->apply_factor(problem_.load_at(u_), a_)) return false;
  negative_pivots_ = tangent_->negative_eigenvalues();
  return true;
}

bool NonlinearSolver::tangent_response(bool guess) {
  negative_pivots_ = -1;
  if (!tangent_->assemble(u_, s_)) return false;
  if (!tangent_->solve(problem_.load_at(u_), a_, guess)) return false;
  inertia_of_response();
  return true;
}

bool NonlinearSolver::tangent_responses(Vec r, Vec b) {
  negative_pivots_ = -1;
  if (!tangent_->assemble(u_, s_)) return false;
  if (!tangent_->solve_pair(problem_.load_at(u_), a_, true, r, b)) return false;
  inertia_of_response();
  return true;
}

void NonlinearSolver::inertia_of_response() {
  // The inertia of K(u_) is known only from a factor of K(u_) itself. (LU: the symmetric part's,
  // one more factorisation, is taken at the final state only: correct().)
  if (tangent_->factor_is_current() && !tangent_->lu()) negative_pivots_ = tangent_->negative_eigenvalues();
}

bool NonlinearSolver::factorise_here() {
  negative_pivots_ = -1;
  if (!tangent_->assemble(u_, s_) || !tangent_->factorise()) return false;
  negative_pivots_ = tangent_->negative_eigenvalues();
  return true;
}

bool NonlinearSolver::check_stability_here() {
  negative_pivots_ = -1;
  if (!tangent_->assemble(u_, s_)) return false;
  pseudo_random_vector(v_);
  negative_pivots_ = tangent_->stability(v_);
  return negative_pivots_ >= 0;
}

}  // namespace hypershape::solver
