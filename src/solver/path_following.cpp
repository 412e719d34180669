/// Path following: displacement control of a target solve, d = max|u| continued to the target
/// in adaptive increments of predictor (tangent step) and bordered-Newton corrector; the control
/// direction; the final state's stability check. Log events HSPredictor / HSCorrector.
#include "hypershape/solver/nonlinear.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>

#include "hypershape/core/error.hpp"
#include "hypershape/core/timer.hpp"
#include "hypershape/core/vec_array.hpp"
#include "hypershape/solver/step_control.hpp"
#include "largest_node.hpp"
#include "log_events.hpp"

namespace hypershape::solver {

/// The load's extremes along a path and where they were (a fold's limit points).
struct NonlinearSolver::LoadExtremes {
  double max_alpha = -INFINITY, d_at_max = 0, min_alpha = INFINITY, d_at_min = 0;
  void add(double alpha, double d) {
    if (alpha > max_alpha) max_alpha = alpha, d_at_max = d;
    if (alpha < min_alpha) min_alpha = alpha, d_at_min = d;
  }
};

namespace {

/// The reason of an equilibrium on target whose own tangent has `negative` negative eigenvalues,
/// with slope = d max|u| / d alpha there (c . K^-1 f_ext). A fold where one eigenvalue is
/// negative and max|u| falls as the load rises: the path (one state per max|u|, continuous)
/// passed a limit point of the load between its start and the target, and its one state with
/// max|u| = target is unstable: no stable equilibrium on target is on this path.
std::string unstable_reason(double target, double alpha, int negative, double slope,
                            const NonlinearSolver::LoadExtremes& e,
                            bool conservative) {
  auto num = [](double x) { return std::to_string(x); };
  if (!conservative)
    return "loss of stability at max|u| = " + num(target) + ", alpha = " + num(alpha) +
           ": the symmetric part of the tangent has " + std::to_string(negative) +
           " negative eigenvalue(s) (stability not proven: a follower load)";
  if (negative == 1 && slope < 0)
    return "fold: max|u| = target lies on an unstable segment of the path (at max|u| = " + num(target) +
           ", alpha = " + num(alpha) + ": d max|u| / d alpha = " + num(slope) +
           " < 0, 1 negative eigenvalue; the path's load before: max " + num(e.max_alpha) + " at max|u| = " +
           num(e.d_at_max) + ", min " + num(e.min_alpha) + " at max|u| = " + num(e.d_at_min) + ")";
  return "loss of stability at max|u| = " + num(target) + ", alpha = " + num(alpha) + ": the tangent has " +
         std::to_string(negative) + " negative eigenvalue(s) (buckling or a bifurcation)";
}

/// Why the path gives up after a failed increment (none: it goes on with the halved `step`).
std::optional<std::string> give_up_reason(int failed_in_a_row, int its, double step, double min_step, int solves,
                           const SolverOptions& opt, const std::string& why) {
  if (failed_in_a_row == opt.max_halvings)
    return std::to_string(failed_in_a_row) + " failed increments in a row (last: " + why + ")";
  if (its >= opt.newton_budget) return why;
  if (std::abs(step) < min_step || solves >= opt.max_increments)
    return "increment below minimum or too many increments (last: " + why + ")";
  return std::nullopt;
}

}  // namespace

const std::vector<PetscInt>& NonlinearSolver::global_of_local() {
  if (global_of_local_.empty()) global_of_local_ = global_of_local_dofs(problem_);
  return global_of_local_;
}

double NonlinearSolver::control_direction(Vec u, Vec fallback, Vec c) {
  DM dm = problem_.dm();
  const int dim = problem_.space().dim();
  Vec ul;
  HS_PETSC(DMGetLocalVector(dm, &ul));
  // The node of the largest |v| (ties: the smallest canonical index, on any rank count).
  auto largest = [&](Vec v) {
    HS_PETSC(VecSet(ul, 0.0));
    HS_PETSC(DMGlobalToLocal(dm, v, INSERT_VALUES, ul));
    core::VecArray<const PetscScalar> a(ul);
    return largest_node(problem_.space(), a.data(), problem_.comm());
  };
  LargestNode top = largest(u);
  if (top.norm2 <= 0.0) top = largest(fallback);  // u = 0: the node that will move most
  const std::int64_t node = top.canonical;
  const PetscInt off = top.here ? top.here->offset : -1;
  const double m = std::sqrt(std::max(top.norm2, 0.0));
  const std::vector<PetscInt>& global = global_of_local();  // collective at its first call
  HS_PETSC(VecSet(c, 0.0));
  if (off >= 0 && m > 0) {  // ul still holds the vector the node was picked from (owned here)
    core::VecArray<const PetscScalar> a(ul);
    for (int i = 0; i < dim; ++i)
      if (global[std::size_t(off + i)] >= 0) HS_PETSC(VecSetValue(c, global[std::size_t(off + i)], a[off + i] / m, INSERT_VALUES));
  }
  HS_PETSC(VecAssemblyBegin(c));
  HS_PETSC(VecAssemblyEnd(c));
  HS_PETSC(DMRestoreLocalVector(dm, &ul));
  PetscReal cu;
  HS_PETSC(VecDot(c, u, &cu));
  HS_PETSC(PetscInfo(snes_.get(), "control node %" PetscInt64_FMT ": |u_k| %.10g\n", (PetscInt64)node, double(cu)));
  return cu;  // = max|u| (0 when u = 0)
}

double NonlinearSolver::constraint(Vec u, Vec fallback, Vec c) {
  if (!arc_) return control_direction(u, fallback, c);
  HS_PETSC(VecCopy(arc_dir_, c));
  PetscReal cu;
  HS_PETSC(VecDot(c, u, &cu));
  return cu - arc_offset_;
}

bool NonlinearSolver::relax_patch(PetscReal& rn) {
  if (!opt_.local_relaxation || !problem_.conservative() || tangent_->multigrid()) return false;
  PetscMPIInt size;
  MPI_Comm_size(problem_.comm(), &size);
  if (size > 1) return false;
  if (!relaxation_) relaxation_ = std::make_unique<LocalRelaxation>(problem_);
  const LocalRelaxation::Result res = relaxation_->relax(u_, s_, r_, c_);
  if (!res.relaxed) return false;
  // With its energy and internal force kept: the corrector's line search starts from them.
  if (!evaluate_known(u_, s_, r_)) throw std::logic_error("a relaxed state is inadmissible");
  HS_PETSC(VecNorm(r_, NORM_2, &rn));
  HS_PETSC(PetscInfo(snes_.get(), "local relaxation: %d dofs, |R| there %g -> %g in %d steps; |R| %g\n", res.dofs,
                     res.before, res.after, res.iterations, double(rn)));
  return true;
}

bool NonlinearSolver::gives_up(int k, double rn, double rn0, const CreepWatch& creep, int its,
                               std::string& why) const {
  if (k == opt_.max_newton)
    why = "no convergence in " + std::to_string(opt_.max_newton) + " Newton iterations";
  else if (k >= 4 && rn > rn0)  // quadratic convergence would be far along by now
    why = "no progress in " + std::to_string(k) + " Newton iterations";
  else if (creep.creeping())
    why = CreepWatch::reason;
  else if (its >= opt_.newton_budget)
    why = "Newton budget of " + std::to_string(opt_.newton_budget) + " iterations spent";
  else
    return false;
  return true;
}

bool NonlinearSolver::correct(double d, double rtol, int& its, std::string& why) {
  LogEvent event(events().corrector);
  const double fnorm = problem_.load_norm();
  const double gtol = 0.1 * opt_.target_rtol * std::abs(d);
  if (!residual_at(u_, s_, r_)) {
    why = "inadmissible state (det F <= 0)";
    return false;
  }
  PetscReal rn, rn0;
  HS_PETSC(VecNorm(r_, NORM_2, &rn));
  rn0 = rn;
  CreepWatch creep(rn);
  // Intermediate states of the path are converged loosely (path_rtol), and so are their Krylov
  // solves: forcing 0.1 there (against krylov_rtol, 1e-3, throughout) cut the factorisations
  // by a third and the Newton iterations by 3% on Random2D draws (3 shapes x 20 load cases).
  constexpr double eta_path = 0.1;
  tangent_->set_forcing(rtol > opt_.rtol ? std::max(eta_path, opt_.tangent.krylov_rtol) : opt_.tangent.krylov_rtol);
  for (int k = 0;; ++k) {
    // Not near round-off, where Newton converges quadratically anyway (relative 1e-5).
    if (rn > opt_.atol + std::max(rtol, 1e-5) * std::abs(s_) * fnorm && relax_patch(rn) && k == 0) rn0 = rn;
    const double m = constraint(u_, a_, c_);
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
    if (refreshed && rn <= opt_.atol + rtol * std::abs(s_) * fnorm && std::abs(g) <= gtol)
      return rtol > opt_.rtol || inertia_at_final_state(why);
    if (gives_up(k, rn, rn0, creep, its, why)) return false;
    ++its;
    // Bordered system: K du - dalpha f = -R, c . du = d - m, with K^-1 f = a and K^-1 R = b
    // (a from the previous iterate's as the initial guess: the tangent moved little).
    if (!tangent_responses(r_, b_)) {
      why = "tangent factorisation or solve failed";
      return false;
    }
    BorderedStep st;
    if (!bordered_step(d, m, rtol, k, st, why)) return false;
    const double dalpha = st.dalpha, dalpha2 = st.dalpha2, lambda = st.lambda;
    HS_PETSC(PetscInfo(snes_.get(), "corrector %d: |R| %g (%g to go), |u_k| - d %g, dalpha %g (c.a %g, c.b %g), step %g, %d negative pivots\n",
                       k, rn, rn / (opt_.atol + rtol * std::abs(s_) * fnorm), g, dalpha, st.ca, st.cb, lambda,
                       negative_pivots_));
    if (lambda == 0.0) {
      why = "line search found no admissible decrease";
      return false;
    }
    if (off_the_path(rtol, lambda)) {
      left_path_ = true;
      why = "indefinite tangent off the path (a damped step with " + std::to_string(negative_pivots_) +
            " negative pivot(s))";
      return false;
    }
    accept_trial(w_, u_);
    s_ += lambda * (dalpha + dalpha2);
    HS_PETSC(VecWAXPY(r_, (1.0 - lambda) * (dalpha + dalpha2), problem_.load_at(u_), b_));  // R(w, s_)
    HS_PETSC(VecNorm(r_, NORM_2, &rn));
    creep.step(lambda, rn);
  }
}

bool NonlinearSolver::bordered_step(double d, double m, double rtol, int k, BorderedStep& st, std::string& why) {
  // From u_ with r_ = R(u_, s_), a_ = K^-1 f and b_ = K^-1 R: Newton's step on the bordered
  // system and the line search's length of it (the trial in w_, its residual in b_); again
  // with U^T |D| U where absolute_pivots() says so.
  for (int attempt = 0;; ++attempt) {
    PetscReal ca, cb;
    HS_PETSC(VecDot(c_, a_, &ca));
    HS_PETSC(VecDot(c_, b_, &cb));
    st.ca = ca, st.cb = cb;
    if (!(std::abs(ca) > 0) || !std::isfinite(ca)) {
      why = "singular bordered system";
      return false;
    }
    st.dalpha = (d - m + cb) / ca;
    // du is Newton's step for equilibrium at the load s + dalpha: take it with the guarded
    // energy line search at that load, and the same fraction of dalpha.
    const double s_full = s_ + st.dalpha;
    HS_PETSC(VecAXPBYPCZ(du_, 1.0, -st.dalpha, 0.0, b_, a_));  // Y = -du = b - dalpha a
    HS_PETSC(VecAXPY(r_, -st.dalpha, problem_.load_at(u_)));  // R(u, s + dalpha)
    st.dalpha2 = chebyshev_corrector(rtol) ? chebyshev_step(s_full, ca, r_) : 0.0;
    st.lambda = backtrack(u_, du_, r_, s_full + st.dalpha2, w_, b_);
    if (attempt > 0 || !(st.lambda < 0.3) || !absolute_pivots(rtol)) return true;
    HS_PETSC(VecAXPY(r_, st.dalpha + st.dalpha2, problem_.load_at(u_)));  // R(u, s) again
    HS_PETSC(PetscInfo(snes_.get(), "corrector %d: step %g with %d negative pivots: again with |D|\n", k, st.lambda,
                       negative_pivots_));
    if (!tangent_->solve_pair(problem_.load_at(u_), a_, false, r_, b_, true)) {
      why = "tangent solve failed";
      return false;
    }
  }
}

bool NonlinearSolver::absolute_pivots(double rtol) const {
  // Opt-in (solver.absolute_pivots, or -path_absolute_pivots, which wins; docs/STABILITY.md,
  // "Modified Newton"): an intermediate iterate whose tangent is indefinite and whose Newton step
  // the line search cut below 0.3 (no descent direction of the energy there: the cells at a
  // clamp's end compressed past what they allow) steps again with U^T |D| U, the same factor with
  // its indefinite 2x2 pivots made positive (Gill, Murray & Wright, Practical Optimization,
  // 4.4.2): a descent direction, one more pair of triangular solves. Not on the last increment:
  // its state on target is reached and classified (stable, or a fold).
  PetscBool on = opt_.absolute_pivots ? PETSC_TRUE : PETSC_FALSE;
  PetscOptionsGetBool(nullptr, nullptr, "-path_absolute_pivots", &on, nullptr);
  return on && rtol > opt_.rtol && negative_pivots_ > 0 && tangent_->absolute_solves();
}

bool NonlinearSolver::off_the_path(double rtol, double lambda) const {
  // An intermediate iterate whose tangent has more negative eigenvalues than the state the
  // increment started from, and whose Newton step the line search cut below 0.3: the predictor
  // overshot into a region where the energy is not convex, away from the path's equilibria (on
  // the path, even on an unstable segment past a limit point, Newton near an equilibrium takes
  // whole steps). Newton there creeps with cut steps and mostly fails after 4-12 iterations
  // (P2 paths on Random2D: a quarter of their Newton iterations were in such increments);
  // failing at once and halving the increment costs one. Only on an increment's first try (the
  // increment before it did not fail): where the path itself turns indefinite (a bifurcation
  // ahead), its retries creep on as before rather than shrink to nothing. Not on the last
  // increment: its state on target is reached and classified (stable, or a fold).
  // Measured side by side with the default (docs/SOLVER.md): Random2D P2 h 0.12, 8
  // shapes x 25 load cases on the unseen seeds 2024 and 777: Newton iterations per load case
  // 21.1 / 20.6 -> 19.0 / 19.0, the same 199 / 200 converged; Random2D P1 h 0.04, 1000 load
  // cases on each of the seeds 777, 2024, 31337: 14.9 / 11.7 / 13.7 -> 14.3 / 11.2 / 13.2, p99
  // 98 / 51 / 79 -> 99 / 42 / 63, but 996 / 999 / 996 converged against 997 / 999 / 996; the
  // Random3D preset, 200 load cases of seed 90210: 198 against 200 converged. Near bifurcations
  // another path is another outcome, and these lost more than they won: so it is off by default.
  return opt_.abandon_off_path && may_leave_ && rtol > opt_.rtol &&
         negative_pivots_ > std::max(pivots_at_start_, 0) && lambda < 0.3;
}

bool NonlinearSolver::inertia_at_final_state(std::string& why) {
  // The final state's stability check needs the inertia of its own tangent: with a kept factor
  // (of an earlier state) it is factorised here, once per target solve.
  if (opt_.tangent.reuse && !factorise_here()) {
    why = "tangent factorisation at the final state failed";
    return false;
  }
  // With multigrid no factor gives the inertia: the smallest eigenvalue's sign does; with LU (a
  // follower load) the symmetric part's LDL^T does.
  if ((tangent_->multigrid() || tangent_->lu()) && !check_stability_here()) {
    why = "tangent at the final state could not be formed or factorised";
    return false;
  }
  return true;
}

bool NonlinearSolver::increment(double d_next, bool last, int& its, std::string& why) {
  left_path_ = false;
  return predict(d_next, why) && correct(d_next, last ? opt_.rtol : opt_.path_rtol, its, why);
}

bool NonlinearSolver::predict(double d_next, std::string& why) {
  LogEvent event(events().predictor);
  pivots_at_start_ = negative_pivots_;
  // Tangent predictor to c . u = d_next: from an equilibrium at s, dalpha a is Newton's step
  // at the load s + dalpha. Taken with the guarded energy line search: never an inverted
  // state, and damped where a linearised large rotation would stretch a nearly
  // incompressible body. (Shortening the increment to the damped length instead cost more
  // increments than it saved: measured on Random2D draws.)
  const double m = constraint(u_, a_, c_);
  PetscReal ca;
  HS_PETSC(VecDot(c_, a_, &ca));
  // c . a = d max|u| / d alpha along the path; negative past a limit point of the load (the
  // path goes on at a falling load: displacement control passes limit points).
  if (!(std::isfinite(ca) && ca != 0.0)) {
    why = "singular tangent: max|u| does not respond to the load";
    return false;
  }
  const double dalpha = (d_next - m) / ca;
  double s_pred = s_ + dalpha;
  HS_PETSC(VecAXPBY(du_, -dalpha, 0.0, a_));  // Y = -dalpha a
  // With the direct factor a_ was solved with: not with multigrid or a kept factor's Krylov
  // solves (no factor, or one of another tangent), nor on the arc-length path (another constraint).
  if (opt_.predictor == Predictor::second_order && !arc_ && !tangent_->multigrid() && !opt_.tangent.reuse &&
      tangent_->has_factor())
    second_order_term(dalpha, ca, s_pred);
  if (!residual_at(u_, s_pred, r_)) throw std::logic_error("a converged state is inadmissible");
  const double lambda = backtrack(u_, du_, r_, s_pred, w_, b_);
  if (lambda > 0.0) {
    accept_trial(w_, u_);
    s_ += lambda * dalpha;
  }
  return true;
}

bool NonlinearSolver::second_order_term(double dalpha, double ca, double& s_pred) {
  // Along the path R(u(alpha), alpha) = F_int(u) - alpha f_ext = 0: K u' = f_ext and
  // K u'' = -D^2 F_int[u', u']. With v = dalpha u', the symmetric difference
  //   q = (R(u + v, s + dalpha) + R(u - v, s - dalpha)) / 2 - R(u, s) = D^2 F_int[v, v] / 2 + O(|v|^4)
  // (the load terms cancel), so u + v - K^-1 q is the path to second order. A nearly
  // incompressible body's tangent step stretches where it rotates (its volume error grows
  // with the square of the rotation); the second-order term takes most of that back, so the
  // corrector starts nearer the path (the disk at P2: a third of the Newton iterations).
  // Where the term is large against v, the path bends too much over the step for a Taylor
  // series: the tangent step alone, as before. The ratio: measured on Random2D P2 (seed 2024,
  // 20 x 25): increments with |K^-1 q| <= 0.05 |v| took 1.6 corrector iterations and none failed,
  // 0.05-0.1: 2.8 and a tenth failed, above 0.1 mostly failed; Newton iterations per load case
  // with the term up to 0.05 / 0.1 / 0.15 / 0.3 / always: -6% / -15% / -16% / -12% / -2%.
  constexpr double kMaxCurvatureRatio = 0.1;
  const double ratio = curvature_along_step(s_, dalpha, r_);
  HS_PETSC(PetscInfo(snes_.get(), "second-order term: |K^-1 q| / |v| = %g%s\n", ratio,
                     ratio >= 0 && ratio <= kMaxCurvatureRatio ? "" : " (not used)"));
  if (!(ratio >= 0 && ratio <= kMaxCurvatureRatio)) return false;
  // step = v - K^-1 q + dalpha2 a, with dalpha2 such that c . step = dalpha c . a (the increment's
  // max|u|).
  s_pred += add_curvature_term(ca);
  return true;
}

double NonlinearSolver::curvature_along_step(double s, double ds, Vec q) {
  if (!curvature_) HS_PETSC(VecDuplicate(u_, curvature_.out()));
  Vec k2 = curvature_;
  HS_PETSC(VecWAXPY(w_, -1.0, du_, u_));  // u + v: the line search's first trial where the term is not taken
  if (!evaluate_ahead(w_, s + ds, q)) return -1;
  HS_PETSC(VecWAXPY(w_, 1.0, du_, u_));  // u - v
  if (!problem_.residual(w_, s - ds, k2)) return -1;
  HS_PETSC(VecAXPBY(q, 0.5, 0.5, k2));
  if (!residual_at(u_, s, k2)) return -1;
  HS_PETSC(VecAXPY(q, -1.0, k2));
  // With the factor a_ was solved with (unrefined where it is single precision: a correction).
  if (!tangent_->apply_factor(q, k2, false)) return -1;
  PetscReal nk2, nv;
  HS_PETSC(VecNorm(k2, NORM_INFINITY, &nk2));
  HS_PETSC(VecNorm(du_, NORM_INFINITY, &nv));
  return nv > 0 && std::isfinite(nk2) ? double(nk2 / nv) : -1;
}

double NonlinearSolver::add_curvature_term(double ca) {
  PetscReal ck2;
  HS_PETSC(VecDot(c_, curvature_, &ck2));
  const double dalpha2 = ck2 / ca;
  HS_PETSC(VecAXPBYPCZ(du_, 1.0, -dalpha2, 1.0, curvature_, a_));  // du_ = -step
  return dalpha2;
}

bool NonlinearSolver::chebyshev_corrector(double rtol) const {
  return opt_.corrector == Corrector::chebyshev && rtol <= opt_.rtol && !arc_ && !opt_.tangent.reuse &&
         !tangent_->multigrid() && tangent_->has_factor();
}

double NonlinearSolver::chebyshev_step(double s, double ca, Vec r) {
  // Chebyshev's method on the bordered system (u, alpha): Newton's step delta plus z with
  // [K -f; c^T 0] z = [-q; 0], q = D^2 R[delta, delta] / 2 by a symmetric difference (the
  // constraint is linear and alpha enters R linearly). Near a solution the error falls with its
  // cube, so the last increment, converged to rtol, takes about one iteration fewer; the
  // intermediate ones, converged to path_rtol in one or two, would pay the two residuals for
  // little. Where the term is longer than delta the residual is far from quadratic over the
  // step, and Newton's step alone goes to the line search. Measured (Newton iterations,
  // deterministic; docs/SOLVER.md): Random2D P2 seed 2024, 20 x 25: 8045 -> 7402 (in every
  // increment, the term up to 0.3 of delta: 7661 at 1.13x the CPU); P1: 4891 -> 4389; Random3D
  // seed 90210, 10 x 20: 1995 -> 1768 (in every increment 1733, at 1.03x the CPU: a residual
  // costs a fair share of a Newton iteration there too); with the term up to 0.3 of delta: 2D P2
  // 7381 (the last increment), 3D 1988 (every increment; one load case lost).
  constexpr double kMaxRatio = 1.0;
  Vec q = b_;  // free until the line search
  const double ratio = curvature_along_step(s, 0.0, q);
  HS_PETSC(PetscInfo(snes_.get(), "corrector's second-order term: |K^-1 q| / |delta| = %g%s\n", ratio,
                     ratio >= 0 && ratio <= kMaxRatio ? "" : " (not used)"));
  if (!(ratio >= 0 && ratio <= kMaxRatio)) return 0.0;
  const double dalpha2 = add_curvature_term(ca);
  HS_PETSC(VecAXPY(r, -dalpha2, problem_.load_at(u_)));
  return dalpha2;
}

void NonlinearSolver::finish_path(TargetResult& t, bool at_target) {
  t.max_displacement = problem_.max_displacement(u_);
  t.alpha = s_;
  t.negative_pivots = negative_pivots_;
  t.converged = at_target && !(negative_pivots_ > 0) && s_ >= 0;
  if (at_target && s_ < 0)
    t.reason = "max|u| = target reached only with the scaled load reversed (alpha = " + std::to_string(s_) + " < 0)";
  if (t.converged) {
    // Leave the SNES as a load-controlled solve would (set up, callbacks at this load); at a
    // converged state this is one residual evaluation and zero Newton iterations.
    SolveResult check;
    t.converged = newton(s_, check);
    t.newton_iterations += check.newton_iterations;
    t.reason = t.converged ? "target reached" : "final check: " + check.reason;
  }
}

bool NonlinearSolver::unstable_on_target(double d, const LoadExtremes& extremes, TargetResult& t) {
  // An equilibrium whose tangent is indefinite: not a minimum of the energy, so not a state the
  // loaded body rests in (it buckles away from it). Only the final state is checked: the
  // elastic equilibria are path-independent, and intermediate states are converged to path_rtol
  // only, where the inertia of a state far from equilibrium would reject good paths (measured:
  // 25 against 13 such failures in 1000 Random2D load cases). Judged and classified on this
  // state's own tangent (the corrector's last factor is one Newton step older): its inertia and
  // d max|u| / d alpha = c . K^-1 f_ext. A follower load keeps the check of its tangent's
  // symmetric part (no energy, no fold to classify).
  if (negative_pivots_ <= 0) return false;  // the corrector's last factor was positive definite
  const int older = negative_pivots_;
  PetscReal slope = 0;
  if (problem_.conservative() && factorise_here() && tangent_->apply_factor(problem_.load(), w_)) {
    control_direction(u_, w_, c_);
    HS_PETSC(VecDot(c_, w_, &slope));
  }
  if (negative_pivots_ < 0) negative_pivots_ = older;
  if (negative_pivots_ <= 0) return false;
  t.reason = unstable_reason(d, s_, negative_pivots_, slope, extremes, problem_.conservative());
  return true;
}

/// The first step of a path from max|u| = d to `target`. At a load case's start (`fresh`: from
/// rest or from the fixed loads' state), at most the hint the earlier load cases of this problem
/// left (next_hint: their load differs, their difficulty is alike): measured on Random2D draws,
/// this halves the discarded increments against a first try at the whole target
/// (scripts/bench_generate.sh).
double NonlinearSolver::first_step(double target, double d, bool fresh) const {
  const double step = target - d;
  return fresh && step > 0 && step_hint_ > 0 ? std::min(step, step_hint_) : step;
}

bool NonlinearSolver::start_under_fixed_loads(double target, int& its) {
  // Measured on multi_load2d (gravity fixed under three tractions; 20 shapes x 50 load cases):
  // from u = 0 the first corrector met gravity and the traction at once; where gravity alone
  // moves another node than the traction (a hanging tip) by more than the increment, no state
  // near rest has that max|u|, and the corrector made no progress down to increments of 1/32 of
  // the target (14 of 15 failures there).
  if (!problem_.residual(u_, 0.0, r_)) return false;
  PetscReal f0;
  HS_PETSC(VecNorm(r_, NORM_2, &f0));
  // Converged as an intermediate state of the path is (path_rtol; the final one is to rtol).
  SolveResult r;
  const bool ok = newton(0.0, r, f0, opt_.path_rtol);
  its += r.newton_iterations;
  HS_PETSC(PetscInfo(snes_.get(), "fixed loads alone (|R(0)| %g): %s in %d Newton its, max|u| %g\n", double(f0),
                     ok ? "converged" : r.reason.c_str(), r.newton_iterations, problem_.max_displacement(u_)));
  if (!ok) {
    HS_PETSC(VecZeroEntries(u_));
    return false;
  }
  // The node the fixed loads move most need not be the scaled load's: where the scaled load first
  // lowers max|u| (it lifts the hanging node), displacement control from here takes alpha
  // negative (measured: 492 of those 1000 load cases reached their target with the load
  // reversed); where it barely moves that node, the corrector overshoots alpha and the control
  // node switches (7 of their 1000 failed so). Load steps first, doubling, until max|u| grows
  // with alpha at a quarter of the rate of the node the scaled load moves most.
  for (int k = 0; k < 12; ++k) {
    if (!tangent_response(false)) return false;
    const double m = control_direction(u_, a_, c_);
    const double response = problem_.max_displacement(a_);
    PetscReal slope;
    HS_PETSC(VecDot(c_, a_, &slope));
    HS_PETSC(PetscInfo(snes_.get(), "under fixed loads at alpha %g: max|u| %g, d max|u| / d alpha %g (largest %g)\n", s_,
                       m, double(slope), response));
    if (slope > 0.25 * response || m >= target) return true;
    // The first step: where the scaled load alone would move its node as far as the fixed ones;
    // then doubling alpha.
    if (!load_step(s_ > 0 ? s_ : m / response, f0, its)) return true;  // a_ is this state's
  }
  return false;
}

bool NonlinearSolver::load_step(double step, double fixed_norm, int& its) {
  HS_PETSC(VecCopy(u_, backup_));
  for (int halving = 0; halving < 4; ++halving, step *= 0.5) {
    SolveResult r;
    const bool ok = newton(s_ + step, r, fixed_norm, opt_.path_rtol);
    its += r.newton_iterations;
    if (ok) {
      s_ += step;
      return true;
    }
    HS_PETSC(VecCopy(backup_, u_));
  }
  return false;
}

TargetResult NonlinearSolver::follow_path(double target, double start, int spent) {
  if (!(target > 0) || !std::isfinite(target)) {
    TargetResult t;
    t.reason = "target max|u| must be positive";
    return t;
  }
  const bool fresh = s_ == 0 && problem_.max_displacement(u_) == 0;  // a load case's start
  if (!fresh || !problem_.has_fixed_load()) return path(target, start, spent, PathStart::here);
  // With fixed loads, from rest first: it is the cheaper start where it works (from the fixed
  // loads' state, measured on the catalogue's fixed pressures: 5.4 -> 7.9 Newton iterations per
  // load case, organ_pressure3d 12.8 -> 16.0, the same equilibria). Where its first increment
  // fails, or it reaches the target only at alpha < 0, again from the fixed loads' state.
  TargetResult rest = path(target, start, spent, PathStart::rest_once);
  if (rest.converged || (rest.increments > 0 && s_ >= 0)) return rest;
  HS_PETSC(PetscInfo(snes_.get(), "from rest: %s; again from the fixed loads' equilibrium\n", rest.reason.c_str()));
  HS_PETSC(VecZeroEntries(u_));
  s_ = 0;
  TargetResult t = path(target, start, spent + rest.newton_iterations, PathStart::fixed_loads);
  t.solves += rest.solves;
  t.newton_iterations += rest.newton_iterations;
  t.failed_increments += rest.failed_increments + rest.increments;
  t.off_path_increments += rest.off_path_increments;
  t.recovery_iterations += rest.newton_iterations;
  t.seconds_first_solve = rest.seconds_first_solve;
  return t;
}

TargetResult NonlinearSolver::path(double target, double start, int spent, PathStart how) {
  TargetResult t;
  int its = spent;  // the Newton budget counts what the target solve spent before
  double d = problem_.max_displacement(u_);
  const bool fresh = d == 0 && s_ == 0;  // a load case's start (not a branch switch's)
  const bool ready = how == PathStart::fixed_loads && start_under_fixed_loads(target, its);
  const double d_start = d = problem_.max_displacement(u_);
  // From rest, K(0) is factorised once per problem where a second factor is cheap to keep
  // (Tangent::use_rest_factor: in 2D, and in 3D with single-precision factors).
  const bool from_rest = d == 0;
  if (!ready && !(from_rest ? rest_response() : tangent_response(false))) {
    t.reason = "tangent factorisation or solve failed at the start";
    return t;
  }
  double step = first_step(target, d, fresh);
  bool first_accepted = true;
  int failed_in_a_row = 0;
  const double growth = step_growth(opt_.step_growth, problem_.space().dim());
  // Increments below 1e-3 of the way (or min_increment, if larger) are a stalled path: it
  // creeps along a limit point (measured: the budget spent on increments of 1e-4 of the way).
  const double min_step = std::abs(target - d) * std::max(opt_.min_increment, 1e-3);
  std::string why;
  LoadExtremes extremes;
  extremes.add(s_, d);
  while (true) {
    const bool last = std::abs(target - d) <= std::abs(step) * (1 + 1e-12);
    const double d_next = last ? target : d + step;
    HS_PETSC(VecCopy(u_, backup_));
    HS_PETSC(VecCopy(a_, a0_));
    const double s_backup = s_;
    const int its_before = its;
    ++t.solves;
    may_leave_ = failed_in_a_row == 0;  // see off_the_path
    const bool ok = increment(d_next, last, its, why);
    if (t.solves == 1) t.seconds_first_solve = core::now_seconds() - start;
    HS_PETSC(PetscInfo(snes_.get(), "path to %g: %g -> %g%s: %s in %d Newton its (alpha %g)\n", target, d, d_next,
                       last ? " (last)" : "", ok ? "converged" : why.c_str(), its - its_before, s_));
    if (ok) {
      ++t.increments;
      if (last && unstable_on_target(d_next, extremes, t)) {
        d = d_next;
        break;
      }
      extremes.add(s_, d_next);
      failed_in_a_row = 0;
      if (first_accepted && fresh)
        step_hint_ = next_hint(step_hint_, d_next - d_start, last, t.failed_increments == 0, its - its_before);
      first_accepted = false;
      d = d_next;
      if (last) break;
      step = next_step(step, its - its_before, growth);
      continue;
    }
    ++t.failed_increments;
    t.off_path_increments += left_path_;
    t.recovery_iterations += its - its_before;
    restore_increment(s_backup);
    step = 0.5 * (d_next - d);  // half the increment that failed (step may have been longer)
    if (how == PathStart::rest_once && first_accepted) {
      t.reason = "first increment from rest failed (" + why + ")";
      break;
    }
    if (auto reason = give_up_reason(++failed_in_a_row, its, step, min_step, t.solves, opt_, why)) {
      t.reason = *reason;
      break;
    }
  }
  t.newton_iterations = its - spent;
  finish_path(t, d == target);
  return t;
}

double NonlinearSolver::arc_start() {
  HS_PETSC(VecZeroEntries(u_));
  s_ = 0;
  PetscReal an = 0;
  if (!rest_response()) return 0;
  HS_PETSC(VecNorm(a_, NORM_2, &an));
  const double amax = problem_.max_displacement(a_);
  if (!(an > 0) || !(amax > 0) || !std::isfinite(an)) return 0;
  HS_PETSC(VecAXPBY(arc_dir_, 1.0 / an, 0.0, a_));
  return an / amax;
}

void NonlinearSolver::restore_increment(double s) {
  HS_PETSC(VecCopy(backup_, u_));
  HS_PETSC(VecCopy(a0_, a_));
  s_ = s;
}

TargetResult NonlinearSolver::arc_path(double target, double start) {
  TargetResult t;
  int its = 0;
  std::string why;
  // Lengths along the path are measured in |u|_2; a step of `scale` moves max|u| by about one
  // unit at the start. The first increment: an eighth of the target's max|u|.
  const double scale = arc_start();
  if (!(scale > 0)) {
    t.reason = "tangent factorisation or solve failed at rest";
    return t;
  }
  double step = 0.125 * target * scale;
  const double min_step = 1e-3 * target * scale;
  arc_ = true;
  int failed_in_a_row = 0;
  const double growth = step_growth(opt_.step_growth, problem_.space().dim());
  bool crossed = false, landing = false;
  while (true) {
    if (its >= opt_.newton_budget) {
      why = "Newton budget of " + std::to_string(opt_.newton_budget) + " iterations spent";
      break;
    }
    if (t.solves >= 4 * opt_.max_increments) {
      why = "too many increments (last: " + why + ")";
      break;
    }
    HS_PETSC(VecCopy(u_, backup_));
    HS_PETSC(VecCopy(a_, a0_));
    HS_PETSC(VecCopy(arc_dir_, arc_prev_dir_));
    const double s_backup = s_;
    PetscReal offset;
    HS_PETSC(VecDot(arc_dir_, u_, &offset));
    arc_offset_ = offset;
    const int its_before = its;
    ++t.solves;
    may_leave_ = failed_in_a_row == 0;
    const bool ok = increment(step, false, its, why);
    HS_PETSC(PetscInfo(snes_.get(), "arc-length: step %g: %s in %d Newton its (alpha %g, max|u| %g)\n", step,
                       ok ? "converged" : why.c_str(), its - its_before, s_, problem_.max_displacement(u_)));
    if (!ok) {
      ++t.failed_increments;
      t.recovery_iterations += its - its_before;
      restore_increment(s_backup);
      step *= 0.5;
      if (++failed_in_a_row == opt_.max_halvings || step < min_step) {
        why = std::to_string(failed_in_a_row) + " failed increments in a row (last: " + why + ")";
        break;
      }
      continue;
    }
    ++t.increments;
    failed_in_a_row = 0;
    const double m = problem_.max_displacement(u_);
    if (m >= target && s_ > 0) {
      // Past the target: where it overshot by more than a quarter of this increment's rise in
      // max|u|, the increment again, shortened to end just past the target (the way back under
      // displacement control is then short).
      const double m0 = problem_.max_displacement(backup_);
      if (!landing && m - target > 0.25 * (m - m0) && m > m0) {
        landing = true;
        restore_increment(s_backup);
        step *= std::min(1.0, 1.1 * (target - m0) / (m - m0));
        HS_PETSC(VecCopy(arc_prev_dir_, arc_dir_));
        continue;
      }
      crossed = true;
      break;
    }
    landing = false;
    // The next direction: the secant of this increment (it goes on along the path where max|u|
    // turns back or the load passes a limit point).
    HS_PETSC(VecWAXPY(arc_dir_, -1.0, backup_, u_));
    PetscReal len;
    HS_PETSC(VecNormalize(arc_dir_, &len));
    step = next_step(step, its - its_before, growth);
  }
  arc_ = false;
  if (!crossed) {
    t.reason = why;
    t.newton_iterations = its;
    t.max_displacement = problem_.max_displacement(u_);
    t.alpha = s_;
    return t;
  }
  // max|u| passed the target on this increment: back to it under displacement control.
  t.newton_iterations = its;
  TargetResult p = path(target, start, its, PathStart::here);
  p.add_earlier(t, false);
  return p;
}

}  // namespace hypershape::solver
