#include "hypershape/solver/nonlinear.hpp"

#include "hypershape/core/timer.hpp"
#include "hypershape/core/vec_array.hpp"
#include <petscmat.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
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
  for (core::VecH* v : {&a_, &a0_, &b_, &c_, &du_, &w_, &v_, &v0_}) *v = problem.create_vector();
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
  configure_direct_solver(ksp, problem.comm(), problem.space().dim());
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
    ++self->snes_linear_.tangent_assemblies;
    if (!self->problem_.jacobian(x, P)) HS_PETSC(SNESSetJacobianDomainError(snes));
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
  HS_PETSC(VecCopy(W, X));
  HS_PETSC(VecCopy(G, F));
  HS_PETSC(SNESLineSearchSetLambda(ls, lambda));
  HS_PETSC(SNESLineSearchComputeNorms(ls));
  HS_PETSC(SNESLineSearchSetReason(ls, SNES_LINESEARCH_SUCCEEDED));
}

double NonlinearSolver::backtrack(Vec X, Vec Y, Vec F, double s, Vec W, Vec G) {
  // Newton step: W = X - lambda Y. Backtrack from lambda = 1 until W is admissible (det F > 0
  // everywhere: finite energy) and either the energy decreases (Armijo) or, where the tangent
  // is not positive definite or the energy change is below round-off, the residual norm does.
  PetscReal fnorm0, slope;
  HS_PETSC(VecNorm(F, NORM_2, &fnorm0));
  HS_PETSC(VecDot(F, Y, &slope));
  slope = -slope;  // d/dlambda of the energy at lambda = 0
  double e0;
  problem_.energy(X, s, e0);
  constexpr double c = 1e-4;
  double lambda = 1.0;
  for (int it = 0; it < 40 && lambda > 1e-10; ++it) {
    HS_PETSC(VecWAXPY(W, -lambda, Y, X));
    double e;
    if (!problem_.energy(W, s, e)) {  // inadmissible: never accept, halve
      lambda *= 0.5;
      continue;
    }
    const bool ok = problem_.residual(W, s, G);
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
  if (!problem_.jacobian(u_, J_)) return std::nullopt;
  ++snes_linear_.numeric_factorizations;
  KSP ksp;
  HS_PETSC(SNESGetKSP(snes_, &ksp));
  HS_PETSC(KSPSetOperators(ksp, J_, J_));
  HS_PETSC(KSPSolve(ksp, problem_.load(), du));
  return problem_.max_displacement(du);
}

TargetResult NonlinearSolver::solve_for_target(double target) {
  const double start = core::now_seconds();
  const LinearCounters linear_before = linear_counters();
  TargetResult t = opt_.control == Control::displacement ? follow_path(target, start)
                                                          : search_target(target, start);
  // (t.solves == 0: the path never started, e.g. no tangent at the initial state: no branch.)
  for (int k = 0; k < opt_.branch_switches && opt_.control == Control::displacement && !t.converged &&
                  target > 0 && t.solves > 0 && t.newton_iterations < opt_.newton_budget;
       ++k)
    switch_branch(target, start, k, t);
  if (opt_.control == Control::displacement && !t.converged && opt_.fallback && target > 0) {
    // Fallback, measured on Random2D draws: where the path cannot be followed (Newton stalls
    // next to a bifurcation), load-controlled solves from the last converged state of the
    // path may still reach a stable equilibrium at the target (a buckled one).
    const TargetResult path = t;
    t = search_target(target, start);
    t.solves += path.solves;
    t.newton_iterations += path.newton_iterations;
    t.failed_increments += path.failed_increments;
    t.increments += path.increments;
    t.recovery_iterations += path.newton_iterations;
    t.reason = (t.converged ? "target reached by load control" : t.reason) +
               " (displacement control: " + path.reason + ")";
  }
  t.seconds_total = core::now_seconds() - start;
  if (t.solves <= 1) t.seconds_first_solve = t.seconds_total;
  t.linear = linear_counters() - linear_before;
  return t;
}

LinearCounters NonlinearSolver::linear_counters() const {
  LinearCounters n = tangent_->counters();
  n += snes_linear_;
  // The SNES's KSP analyses its pattern once, on its first factorisation.
  if (snes_linear_.numeric_factorizations > 0) ++n.symbolic_factorizations;
  return n;
}

bool NonlinearSolver::apply_tangent_factor(Vec x, Vec y) {
  return !tangent_->multigrid() && tangent_->has_factor() && tangent_->apply_factor(x, y);
}

bool NonlinearSolver::rest_response() {
  if (!tangent_->use_rest_factor(u_)) return tangent_response(false);
  negative_pivots_ = -1;
  if (!tangent_->apply_factor(problem_.load(), a_)) return false;
  negative_pivots_ = tangent_->negative_eigenvalues();
  return true;
}

bool NonlinearSolver::tangent_response(bool guess) {
  negative_pivots_ = -1;
  if (!tangent_->assemble(u_)) return false;
  if (!tangent_->solve(problem_.load(), a_, guess)) return false;
  // The inertia of K(u_) is known only from a factor of K(u_) itself.
  if (tangent_->factor_is_current()) negative_pivots_ = tangent_->negative_eigenvalues();
  return true;
}

bool NonlinearSolver::factorise_here() {
  negative_pivots_ = -1;
  if (!tangent_->assemble(u_) || !tangent_->factorise()) return false;
  negative_pivots_ = tangent_->negative_eigenvalues();
  return true;
}

bool NonlinearSolver::check_stability_here() {
  negative_pivots_ = -1;
  if (!tangent_->assemble(u_)) return false;
  pseudo_random_vector(v_);
  negative_pivots_ = tangent_->stability(v_);
  return negative_pivots_ >= 0;
}

double NonlinearSolver::control_direction(Vec u, Vec fallback, Vec c) {
  DM dm = problem_.dm();
  const int dim = problem_.space().dim();
  const MPI_Comm comm = problem_.comm();
  Vec ul, cl;
  HS_PETSC(DMGetLocalVector(dm, &ul));
  HS_PETSC(DMGetLocalVector(dm, &cl));
  // The node of the largest |v| (ties: the smallest canonical index, on any rank count).
  auto largest = [&](Vec v, PetscInt& offset, double& norm2) {
    HS_PETSC(VecSet(ul, 0.0));
    HS_PETSC(DMGlobalToLocal(dm, v, INSERT_VALUES, ul));
    core::VecArray<const PetscScalar> a(ul);
    double best = -1;
    std::int64_t id = INT64_MAX;
    offset = -1;
    for (const auto& n : problem_.space().owned_nodes()) {
      double s = 0;
      for (int i = 0; i < dim; ++i) s += a[n.offset + i] * a[n.offset + i];
      if (s > best || (s == best && n.canonical < id)) best = s, id = n.canonical, offset = n.offset;
    }
    double gbest = best;
    MPI_Allreduce(MPI_IN_PLACE, &gbest, 1, MPI_DOUBLE, MPI_MAX, comm);
    std::int64_t gid = best == gbest ? id : INT64_MAX;
    MPI_Allreduce(MPI_IN_PLACE, &gid, 1, MPI_INT64_T, MPI_MIN, comm);
    if (!(best == gbest && id == gid)) offset = -1;  // another rank owns the node
    norm2 = gbest;
  };
  PetscInt off;
  double m2;
  largest(u, off, m2);
  if (m2 <= 0.0) largest(fallback, off, m2);  // u = 0: the node that will move most
  const double m = std::sqrt(std::max(m2, 0.0));
  HS_PETSC(VecSet(cl, 0.0));
  if (off >= 0 && m > 0) {  // ul still holds the vector the node was picked from
    core::VecArray<const PetscScalar> a(ul);
    core::VecArray<PetscScalar> cv(cl);
    for (int i = 0; i < dim; ++i) cv[off + i] = a[off + i] / m;
  }
  HS_PETSC(DMLocalToGlobal(dm, cl, INSERT_VALUES, c));  // owned entries only
  HS_PETSC(DMRestoreLocalVector(dm, &cl));
  HS_PETSC(DMRestoreLocalVector(dm, &ul));
  PetscReal cu;
  HS_PETSC(VecDot(c, u, &cu));
  return cu;  // = max|u| (0 when u = 0)
}

bool NonlinearSolver::correct(double d, double rtol, int& its, std::string& why) {
  LogEvent event(events().corrector);
  const double fnorm = problem_.load_norm();
  const double gtol = 0.1 * opt_.target_rtol * std::abs(d);
  if (!problem_.residual(u_, s_, r_)) {
    why = "inadmissible state (det F <= 0)";
    return false;
  }
  PetscReal rn, rn0;
  HS_PETSC(VecNorm(r_, NORM_2, &rn));
  rn0 = rn;
  // Intermediate states of the path are converged loosely (path_rtol), and so are their Krylov
  // solves: forcing 0.1 there (against krylov_rtol, 1e-3, throughout) cut the factorisations
  // by a third and the Newton iterations by 3% on Random2D draws (3 shapes x 20 load cases).
  constexpr double eta_path = 0.1;
  tangent_->set_forcing(rtol > opt_.rtol ? std::max(eta_path, opt_.tangent.krylov_rtol) : opt_.tangent.krylov_rtol);
  for (int k = 0;; ++k) {
    const double m = control_direction(u_, a_, c_);
    const double g = m - d;
    if (!std::isfinite(rn)) {
      why = "non-finite residual";
      return false;
    }
    // An intermediate state gets at least one corrector iteration, even where the predictor
    // landed within path_rtol: the next increment's predictor and its inertia need the tangent
    // of this state (a_ and negative_pivots_ would be two states old). Measured on Random2D
    // (8 shapes x 25 load cases, P1): 8 states accepted unrefreshed, the increments after them
    // failed 32 times; with the iteration 14.1 -> 13.3 Newton iterations per load case.
    const bool refreshed = k > 0 || rtol <= opt_.rtol;
    if (refreshed && rn <= opt_.atol + rtol * std::abs(s_) * fnorm && std::abs(g) <= gtol) {
      // The final state's stability check needs the inertia of its own tangent: with a kept
      // factor (of an earlier state) it is factorised here, once per target solve.
      if (rtol <= opt_.rtol && opt_.tangent.reuse && !factorise_here()) {
        why = "tangent factorisation at the final state failed";
        return false;
      }
      // With multigrid no factor gives the inertia: the smallest eigenvalue's sign does.
      if (rtol <= opt_.rtol && tangent_->multigrid() && !check_stability_here()) {
        why = "tangent at the final state could not be formed or factorised";
        return false;
      }
      return true;
    }
    if (k == opt_.max_newton) {
      why = "no convergence in " + std::to_string(opt_.max_newton) + " Newton iterations";
      return false;
    }
    if (k >= 4 && rn > rn0) {  // quadratic convergence would be far along by now
      why = "no progress in " + std::to_string(k) + " Newton iterations";
      return false;
    }
    if (its >= opt_.newton_budget) {
      why = "Newton budget of " + std::to_string(opt_.newton_budget) + " iterations spent";
      return false;
    }
    ++its;
    // Bordered system: K du - dalpha f = -R, c . du = d - m, with K^-1 f = a and K^-1 R = b
    // (a from the previous iterate's as the initial guess: the tangent moved little).
    if (!tangent_response(true) || !tangent_->solve(r_, b_, false)) {
      why = "tangent factorisation or solve failed";
      return false;
    }
    PetscReal ca, cb;
    HS_PETSC(VecDot(c_, a_, &ca));
    HS_PETSC(VecDot(c_, b_, &cb));
    if (!(std::abs(ca) > 0) || !std::isfinite(ca)) {
      why = "singular bordered system";
      return false;
    }
    const double dalpha = (d - m + cb) / ca;
    // du is Newton's step for equilibrium at the load s + dalpha: take it with the guarded
    // energy line search at that load, and the same fraction of dalpha.
    const double s_full = s_ + dalpha;
    HS_PETSC(VecAXPBYPCZ(du_, 1.0, -dalpha, 0.0, b_, a_));  // Y = -du = b - dalpha a
    HS_PETSC(VecAXPY(r_, -dalpha, problem_.load()));       // R(u, s + dalpha)
    const double lambda = backtrack(u_, du_, r_, s_full, w_, b_);
    HS_PETSC(PetscInfo(snes_.get(), "corrector %d: |R| %g (%g to go), |u_k| - d %g, dalpha %g, step %g, %d negative pivots\n", k, rn,
                       rn / (opt_.atol + rtol * std::abs(s_) * fnorm), g, dalpha, lambda, negative_pivots_));
    if (lambda == 0.0) {
      why = "line search found no admissible decrease";
      return false;
    }
    HS_PETSC(VecCopy(w_, u_));
    s_ += lambda * dalpha;
    HS_PETSC(VecWAXPY(r_, (1.0 - lambda) * dalpha, problem_.load(), b_));  // R(w, s_)
    HS_PETSC(VecNorm(r_, NORM_2, &rn));
  }
}

void NonlinearSolver::pseudo_random_vector(Vec v) {
  // Keyed by the canonical node numbers (the same on any rank count), so that no mode is
  // missing from it by symmetry.
  DM dm = problem_.dm();
  const int dim = problem_.space().dim();
  Vec xl;
  HS_PETSC(DMGetLocalVector(dm, &xl));
  HS_PETSC(VecSet(xl, 0.0));
  {
    core::VecArray<PetscScalar> x(xl);
    for (const auto& n : problem_.space().owned_nodes())
      for (int i = 0; i < dim; ++i) {
        std::uint64_t h = std::uint64_t(n.canonical) * 0x9E3779B97F4A7C15ull + std::uint64_t(i + 1);
        h ^= h >> 31;
        h *= 0xBF58476D1CE4E5B9ull;
        h ^= h >> 29;
        x[n.offset + i] = double(h >> 11) / double(1ull << 53) - 0.5;
      }
  }
  HS_PETSC(DMLocalToGlobal(dm, xl, INSERT_VALUES, v));
  HS_PETSC(DMRestoreLocalVector(dm, &xl));
}

double NonlinearSolver::softest_mode() {
  pseudo_random_vector(v_);
  for (int k = 0; k < 8; ++k) {  // K is factored (factorise_here): 8 back-substitutions
    PetscReal n;
    HS_PETSC(VecNormalize(v_, &n));
    tangent_->apply_factor(v_, w_);
    HS_PETSC(VecCopy(w_, v_));
  }
  PetscReal vmax, vv, vkv;
  HS_PETSC(VecNorm(v_, NORM_INFINITY, &vmax));
  HS_PETSC(VecScale(v_, 1.0 / vmax));
  HS_PETSC(MatMult(tangent_->matrix(), v_, w_));
  HS_PETSC(VecDot(v_, w_, &vkv));
  HS_PETSC(VecDot(v_, v_, &vv));
  return vkv / vv;
}

bool NonlinearSolver::curvature_step(double radius, double mu0, int negative) {
  // Moré-Sorensen-like: where K is indefinite, shift it just past its most negative eigenvalue
  // (estimated by the softest mode) and add a move along that mode so that the step fills the
  // trust region. The former fixed shifts (mu0, 4 mu0, ...; lowered by 4 after full steps) with a
  // straight-line move of eps along the mode cycled at saddle plateaus: the shifted steps were
  // 1e-3 long and led back (seed 777, shape 5, load 26: the same 4 iterations 12 times).
  double mu = 0, dsign = 0;
  if (negative > 0) {
    const double lam = softest_mode();  // v_; the factor in use is of K itself
    if (lam < 0) {
      PetscReal rv;
      HS_PETSC(VecDot(r_, v_, &rv));
      dsign = rv > 0 ? -1.0 : 1.0;  // the energy's slope along +v_ is R . v_
    }
    double target = lam < 0 ? -2 * lam : mu0;
    for (int k = 0; k < 12; ++k, target *= 4) {
      tangent_->shift(target - mu);
      mu = target;
      if (tangent_->factorise() && tangent_->negative_eigenvalues() == 0) break;
      if (k == 11) return false;
    }
  }
  if (!tangent_->apply_factor(r_, du_)) return false;  // u - du_: the (shifted) Newton step
  PetscReal dmax;
  HS_PETSC(VecNorm(du_, NORM_INFINITY, &dmax));
  if (dsign != 0 && dmax < radius) HS_PETSC(VecAXPY(du_, -dsign * (radius - dmax), v_));
  HS_PETSC(VecNorm(du_, NORM_INFINITY, &dmax));
  if (dmax > radius) HS_PETSC(VecScale(du_, radius / dmax));
  HS_PETSC(PetscInfo(snes_.get(), "minimise: %d negative pivot(s), shift %g, step %g (radius %g)%s\n", negative, mu,
                     std::min(double(dmax), radius), radius, dsign != 0 ? ", along negative curvature" : ""));
  return true;
}

bool NonlinearSolver::minimise(double s, double eps, int& its, std::string& why) {
  const double tol = opt_.atol + opt_.rtol * std::abs(s) * problem_.load_norm();
  double mu0 = 0, radius = eps;
  for (int k = 0;; ++k) {
    if (!problem_.residual(u_, s, r_)) {
      why = "inadmissible state (det F <= 0)";
      return false;
    }
    PetscReal rn;
    HS_PETSC(VecNorm(r_, NORM_2, &rn));
    if (!std::isfinite(rn)) {
      why = "non-finite residual";
      return false;
    }
    if (k == 4 * opt_.max_newton || its >= opt_.newton_budget) {
      why = "energy minimisation: no convergence in " + std::to_string(k) + " iterations";
      return false;
    }
    // The inertia of K(u) itself: a factorisation of this very tangent.
    if (!factorise_here()) {
      why = "tangent could not be formed or factorised";
      return false;
    }
    if (negative_pivots_ == 0 && rn <= tol) return true;
    ++its;
    if (mu0 == 0) {  // the shift's scale where no negative eigenvalue is estimated
      HS_PETSC(MatGetDiagonal(tangent_->matrix(), w_));
      PetscReal sum;
      PetscInt n;
      HS_PETSC(VecSum(w_, &sum));
      HS_PETSC(VecGetSize(w_, &n));
      mu0 = 1e-3 * std::abs(sum) / double(n);
    }
    if (!curvature_step(radius, mu0, negative_pivots_)) {
      why = "shifted tangent could not be factorised";
      return false;
    }
    PetscReal ymax;
    HS_PETSC(VecNorm(du_, NORM_INFINITY, &ymax));
    const double lambda = backtrack(u_, du_, r_, s, w_, b_);
    HS_PETSC(PetscInfo(snes_.get(), "minimise %d: |R| %g (%g to go), step %g x %g\n", k, rn, rn / tol, lambda, ymax));
    if (lambda == 0.0) {
      radius = 0.25 * std::min(radius, double(ymax));
      continue;
    }
    HS_PETSC(VecCopy(w_, u_));
    // Grow the region after a full step that filled it, shrink it to what the line search took.
    if (lambda == 1.0 && ymax >= 0.99 * radius) radius = std::min(2 * radius, 20 * eps);
    else if (lambda < 1.0) radius = std::max(lambda * ymax, 1e-3 * eps);
  }
}

void NonlinearSolver::switch_branch(double target, double start, int attempt, TargetResult& t) {
  int its = t.newton_iterations;  // the Newton budget counts the whole target solve
  std::string why;
  if (attempt == 0) {
    HS_PETSC(VecCopy(u_, v0_));
    s0_ = s_;
  } else {  // the state the path left, at a lower load: where the stable branch holds
    HS_PETSC(VecCopy(v0_, u_));
    s_ = s0_ * std::pow(0.7, attempt);
  }
  // Leave the state along the softest mode of the tangent (the buckling mode at a
  // bifurcation, the near-null mode where Newton stalled), by the sign of lower energy.
  LogEvent event(events().branch_switch);
  bool ok = factorise_here();
  if (ok) {
    ++its;
    softest_mode();
    HS_PETSC(VecCopy(u_, backup_));
    double e[2];
    bool adm[2] = {false, false};
    double eps = 0.05 * target;
    // Shorter where both directions invert an element (a state already near inversion).
    for (int tries = 0;; ++tries, eps *= 0.25) {
      for (int k = 0; k < 2; ++k) {
        HS_PETSC(VecWAXPY(w_, k == 0 ? eps : -eps, v_, backup_));
        adm[k] = problem_.energy(w_, s_, e[k]);
      }
      if (adm[0] || adm[1] || tries == 3) break;
    }
    const int pick = adm[0] && (!adm[1] || e[0] <= e[1]) ? 0 : 1;
    ok = adm[pick];
    if (ok) HS_PETSC(VecWAXPY(u_, pick == 0 ? eps : -eps, v_, backup_));
    else why = "both perturbations along the softest mode invert elements";
  } else {
    why = "tangent factorisation failed";
  }
  if (ok) ok = minimise(s_, 0.05 * target, its, why);
  const std::string before = t.reason;
  t.recovery_iterations += its - t.newton_iterations;
  t.newton_iterations = its;
  if (!ok) {
    t.reason = before + "; branch switch failed: " + why;
    return;
  }
  // On the new branch: a stable equilibrium at the same load. Follow it to the target.
  TargetResult p = follow_path(target, start, t.newton_iterations);
  p.solves += t.solves;
  p.newton_iterations += t.newton_iterations;
  p.failed_increments += t.failed_increments;
  p.increments += t.increments;
  p.recovery_iterations += t.recovery_iterations;
  p.reason = p.converged ? "target reached after a branch switch (" + before + ")"
                         : p.reason + " (after a branch switch from: " + before + ")";
  t = p;
}

bool NonlinearSolver::increment(double d_next, bool last, int& its, std::string& why) {
  // Tangent predictor to c . u = d_next: from an equilibrium at s, dalpha a is Newton's step
  // at the load s + dalpha. Taken with the guarded energy line search: never an inverted
  // state, and damped where a linearised large rotation would stretch a nearly
  // incompressible body. (Shortening the increment to the damped length instead cost more
  // increments than it saved: measured on Random2D draws.)
  const double m = control_direction(u_, a_, c_);
  PetscReal ca;
  HS_PETSC(VecDot(c_, a_, &ca));
  // c . a = d max|u| / d alpha along the path; negative past a limit point of the load (the
  // path goes on at a falling load: displacement control passes limit points).
  if (!(std::isfinite(ca) && ca != 0.0)) {
    why = "singular tangent: max|u| does not respond to the load";
    return false;
  }
  const double dalpha = (d_next - m) / ca;
  const double s_pred = s_ + dalpha;
  if (!problem_.residual(u_, s_pred, r_)) throw std::logic_error("a converged state is inadmissible");
  HS_PETSC(VecAXPBY(du_, -dalpha, 0.0, a_));  // Y = -dalpha a
  const double lambda = backtrack(u_, du_, r_, s_pred, w_, b_);
  if (lambda > 0.0) {
    HS_PETSC(VecCopy(w_, u_));
    s_ += lambda * dalpha;
  }
  return correct(d_next, last ? opt_.rtol : opt_.path_rtol, its, why);
}

void NonlinearSolver::finish_path(TargetResult& t, bool at_target) {
  t.max_displacement = problem_.max_displacement(u_);
  t.alpha = s_;
  t.negative_pivots = negative_pivots_;
  t.converged = at_target && !(negative_pivots_ > 0);
  if (t.converged) {
    // Leave the SNES as a load-controlled solve would (set up, callbacks at this load); at a
    // converged state this is one residual evaluation and zero Newton iterations.
    SolveResult check;
    t.converged = newton(s_, check);
    t.newton_iterations += check.newton_iterations;
    t.reason = t.converged ? "target reached" : "final check: " + check.reason;
  }
}

TargetResult NonlinearSolver::follow_path(double target, double start, int spent) {
  TargetResult t;
  if (!(target > 0) || !std::isfinite(target)) {
    t.reason = "target max|u| must be positive";
    return t;
  }
  double d = problem_.max_displacement(u_);
  // From rest in 2D, K(0) is factorised once per problem. Not in 3D: a second MUMPS factor
  // there doubles the factor memory (hundreds of MiB per rank at the 3D presets' sizes) for
  // one factorisation in about ten per load case.
  const bool cached_rest = d == 0 && problem_.space().dim() == 2;
  if (!(cached_rest ? rest_response() : tangent_response(false))) {
    t.reason = "tangent factorisation or solve failed at the start";
    return t;
  }
  double step = target - d;
  // From rest, the first increment is the one the previous load case of this problem took
  // first (its load differs, its difficulty is alike): measured on Random2D draws, this halves
  // the discarded increments against a first try at the whole target (scripts/bench_generate.sh).
  const bool from_rest = d == 0;
  if (from_rest && step_hint_ > 0) step = std::min(step, step_hint_);
  bool first_accepted = true;
  int failed_in_a_row = 0;
  // Increments below 1e-3 of the way (or min_increment, if larger) are a stalled path: it
  // creeps along a limit point (measured: the budget spent on increments of 1e-4 of the way).
  const double min_step = std::abs(target - d) * std::max(opt_.min_increment, 1e-3);
  int its = spent;  // the Newton budget counts what the target solve spent before
  std::string why;
  while (true) {
    const bool last = std::abs(target - d) <= std::abs(step) * (1 + 1e-12);
    const double d_next = last ? target : d + step;
    HS_PETSC(VecCopy(u_, backup_));
    HS_PETSC(VecCopy(a_, a0_));
    const double s_backup = s_;
    const int its_before = its;
    ++t.solves;
    const bool ok = increment(d_next, last, its, why);
    if (t.solves == 1) t.seconds_first_solve = core::now_seconds() - start;
    HS_PETSC(PetscInfo(snes_.get(), "path to %g: %g -> %g%s: %s in %d Newton its (alpha %g)\n", target, d, d_next,
                       last ? " (last)" : "", ok ? "converged" : why.c_str(), its - its_before, s_));
    if (ok && last && negative_pivots_ > 0) {
      // An equilibrium whose tangent is indefinite: not a minimum of the energy, so not a state
      // the loaded body rests in (it buckles away from it). Only the final state is checked:
      // the elastic equilibria are path-independent, and intermediate states are converged
      // to path_rtol only, where the inertia of a state far from equilibrium would reject
      // good paths (measured: 25 against 13 such failures in 1000 Random2D load cases).
      t.reason = "loss of stability at max|u| = " + std::to_string(d_next) + ", alpha = " +
                 std::to_string(s_) + ": the tangent has " + std::to_string(negative_pivots_) +
                 " negative eigenvalue(s) (buckling or a bifurcation)";
      ++t.increments;
      d = d_next;
      break;
    }
    if (ok) {
      ++t.increments;
      failed_in_a_row = 0;
      if (first_accepted && from_rest) step_hint_ = d_next;
      first_accepted = false;
      d = d_next;
      if (last) break;
      // Step control by the corrector's count: double after <= 2 iterations, halve after >= 6.
      // Measured on Random2D (8 x 25, P1): the increment after a doubling failed in 13%, 11%
      // and 18% of cases after 1, 2 and 3 iterations (a failure costs 5.7 iterations, an
      // accepted intermediate increment 3.1); doubling after <= 3 and halving after >= 8
      // (before): 13.3 Newton iterations per load case, this rule 12.6 (0.24 failed increments
      // per load case against 0.34), all 200 converged.
      const int n = its - its_before;
      if (n <= 2) step *= 2.0; else if (n >= 6) step *= 0.5;
      continue;
    }
    ++t.failed_increments;
    t.recovery_iterations += its - its_before;
    HS_PETSC(VecCopy(backup_, u_));
    HS_PETSC(VecCopy(a0_, a_));
    s_ = s_backup;
    step = 0.5 * (d_next - d);  // half the increment that failed (step may have been longer)
    if (++failed_in_a_row == opt_.max_halvings) {
      t.reason = std::to_string(failed_in_a_row) + " failed increments in a row (last: " + why + ")";
      break;
    }
    if (its >= opt_.newton_budget) {
      t.reason = why;
      break;
    }
    if (std::abs(step) < min_step || t.solves >= opt_.max_increments) {
      t.reason = "increment below minimum or too many increments (last: " + why + ")";
      break;
    }
  }
  t.newton_iterations = its - spent;
  finish_path(t, d == target);
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
