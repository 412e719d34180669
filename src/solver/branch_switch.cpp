/// Branch switching: after a path that ended unstable or stalled, leave the state along one of
/// the tangent's modes, minimise the energy there (trust-region Newton with an inertia
/// correction) and follow the new branch to the target. Log event HSBranchSwitch.
#include "hypershape/solver/nonlinear.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "hypershape/core/error.hpp"
#include "hypershape/core/vec_array.hpp"
#include "largest_node.hpp"
#include "log_events.hpp"

namespace hypershape::solver {

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

ModeExtent mode_extent(const physics::Problem& problem, Vec v) {
  DM dm = problem.dm();
  Vec vl;
  HS_PETSC(DMGetLocalVector(dm, &vl));
  HS_PETSC(VecSet(vl, 0.0));
  HS_PETSC(DMGlobalToLocal(dm, v, INSERT_VALUES, vl));
  std::vector<double> s2;
  LargestNode top;
  {
    core::VecArray<const PetscScalar> a(vl);
    top = largest_node(problem.space(), a.data(), problem.comm(), &s2);
  }
  HS_PETSC(DMRestoreLocalVector(dm, &vl));
  ModeExtent e;
  std::array<double, 3> at{};  // summed over ranks: only the owner's is not zero
  if (top.here) at = top.here->x;
  MPI_Allreduce(at.data(), e.at.data(), 3, MPI_DOUBLE, MPI_SUM, problem.comm());
  for (const double s : s2) e.nodes += s > 0.1 * top.norm2;
  MPI_Allreduce(MPI_IN_PLACE, &e.nodes, 1, MPI_LONG, MPI_SUM, problem.comm());
  return e;
}

double NonlinearSolver::shift_scale() {
  // A thousandth of K's mean diagonal: the first shift where no negative eigenvalue is estimated.
  HS_PETSC(MatGetDiagonal(tangent_->matrix(), w_));
  PetscReal sum;
  PetscInt n;
  HS_PETSC(VecSum(w_, &sum));
  HS_PETSC(VecGetSize(w_, &n));
  return 1e-3 * std::abs(sum) / double(n);
}

bool NonlinearSolver::shift_past_lowest_mode(double mu0, double& mu, double& lam) {
  // K + mu I with no negative pivot: mu = -2 lam where the mode nearest zero is K's negative
  // one, else mu0, 4 mu0, ... Where it was not, the mode nearest zero is a positive one (a soft
  // mode of the body: at the unstable states of 11 Random2D switches replayed it always was,
  // Rayleigh quotients 0.016-0.075; lowest eigenvalues -106 to -1988), and inverse
  // iteration with the definite K + mu I finds K's lowest mode instead.
  mu = 0;
  lam = softest_mode();  // v_; the factor in use is of K itself
  const bool negative_found = lam < 0;
  double target = negative_found ? -2 * lam : mu0;
  for (int k = 0; k < 12; ++k, target *= 4) {
    tangent_->shift(target - mu);
    mu = target;
    if (tangent_->factorise() && tangent_->negative_eigenvalues() == 0) break;
    if (k == 11) return false;
  }
  const double nearest_zero = lam;
  if (!negative_found) lam = softest_mode() - mu;  // the matrix and factor are K + mu I's
  if (PetscLogPrintInfo) {  // where it lives (an element-scale crease or the body's buckling)
    const ModeExtent e = mode_extent(problem_, v_);
    HS_PETSC(PetscInfo(snes_.get(), "lowest mode: %g (the mode nearest zero: %g), shift %g; on %ld node(s) around (%g, %g, %g)\n",
                       lam, nearest_zero, mu, e.nodes, e.at[0], e.at[1], e.at[2]));
  }
  return true;
}

bool NonlinearSolver::curvature_step(double radius, double mu0, int negative) {
  // Moré-Sorensen-like: where K is indefinite, shift it just past its most negative eigenvalue
  // and add a move along that eigenvalue's mode so that the step fills the trust region. The
  // former fixed shifts (mu0, 4 mu0, ...; lowered by 4 after full steps) with a straight-line
  // move of eps along the mode cycled at saddle plateaus: the shifted steps were 1e-3 long and
  // led back (seed 777, shape 5, load 26: the same 4 iterations 12 times).
  double mu = 0, dsign = 0;
  if (negative > 0) {
    double lam;
    if (!shift_past_lowest_mode(mu0, mu, lam)) return false;
    if (lam < 0) {
      PetscReal rv;
      HS_PETSC(VecDot(r_, v_, &rv));
      dsign = rv > 0 ? -1.0 : 1.0;  // the energy's slope along +v_ is R . v_
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
  double rn_prev = INFINITY;
  bool full_step = false;  // the last step was the whole Newton step (neither clipped nor cut)
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
    // The cap of 4 max_newton iterations stops a minimisation that wanders on a flat landscape;
    // one in Newton's local phase (the last step whole and |R| at least halved by it) is let
    // finish within the budget. Measured: seed 777, shape 7, load 9 had |R| 3e-4 against a
    // tolerance of 4e-9 at the cap, falling 0.24, 0.07, 0.06, 4e-3, 3e-4 over its last steps.
    const bool converging = full_step && rn < 0.5 * rn_prev;
    if ((k >= 4 * opt_.max_newton && !converging) || its >= opt_.newton_budget) {
      why = "energy minimisation: no convergence in " + std::to_string(k) + " iterations";
      return false;
    }
    rn_prev = rn;
    // The inertia of K(u) itself: a factorisation of this very tangent.
    if (!factorise_here()) {
      why = "tangent could not be formed or factorised";
      return false;
    }
    if (negative_pivots_ == 0 && rn <= tol) return true;
    ++its;
    if (mu0 == 0) mu0 = shift_scale();
    if (!curvature_step(radius, mu0, negative_pivots_)) {
      why = "shifted tangent could not be factorised";
      return false;
    }
    PetscReal ymax;
    HS_PETSC(VecNorm(du_, NORM_INFINITY, &ymax));
    const double lambda = backtrack(u_, du_, r_, s, w_, b_);
    HS_PETSC(PetscInfo(snes_.get(), "minimise %d: |R| %g (%g to go), step %g x %g\n", k, rn, rn / tol, lambda, ymax));
    full_step = lambda == 1.0 && ymax < 0.99 * radius;  // the whole Newton step, not clipped
    if (lambda == 0.0) {
      radius = 0.25 * std::min(radius, double(ymax));
      continue;
    }
    accept_trial(w_, u_);
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
  // Leave the state, by the sign of lower energy, along the tangent's lowest mode where the path
  // ended on target at an unstable state (the buckling mode), along its mode nearest zero where
  // the path stalled before the target (the near-null mode that stopped Newton; measured with the
  // lowest mode there too: Random2D P2 stalls took 104.1 against 103.3 Newton iterations each,
  // and one Random3D stall of 200 was lost).
  LogEvent event(events().branch_switch);
  const double off_target = std::abs(problem_.max_displacement(u_) - target);
  const bool on_target = off_target <= 0.1 * opt_.target_rtol * target;  // correct()'s tolerance
  bool ok = factorise_here();
  if (!ok) why = "tangent factorisation failed";
  if (ok) {
    ++its;
    double mu, lam;
    if (on_target && negative_pivots_ > 0) ok = shift_past_lowest_mode(shift_scale(), mu, lam);
    else softest_mode();
    if (!ok) why = "no shift of the indefinite tangent factorised";
  }
  if (ok) {
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
    else why = "both perturbations along the mode invert elements";
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
  p.add_earlier(t, false);
  p.reason = p.converged ? "target reached after a branch switch (" + before + ")"
                         : p.reason + " (after a branch switch from: " + before + ")";
  t = p;
}

}  // namespace hypershape::solver
