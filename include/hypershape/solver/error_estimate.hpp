#pragma once
/// A posteriori error estimate of a solved load case: the two-level estimate.
///
/// The solution u_h of the coarse problem is prolonged exactly (P, nested spaces) to the same
/// scene on the uniformly refined mesh (mesh::refine_uniform, same degree), and one Newton step
/// of the fine problem is taken from there at the same load:
///   K_f(P u_h) e = -R_f(P u_h),
/// solved by GMRES (at most 40 iterations) with a two-grid preconditioner (PCMG: a factor of the coarse tangent as the
/// coarse level -- the one the nonlinear solve left, or K_c(u_h) factorised here --, P as the
/// interpolation, symmetric Gauss-Seidel smoothing on the fine level; a few iterations, no
/// fine factorisation; Newton on to 1% of the first residual where the estimator is asked to,
/// as the factory does for the mean-dilatation element). P u_h + e is the fine solution
/// u_{h/2} to second order, so e estimates u_{h/2} - u_h, and
///   u - u_h ~ theta e,   theta = 1 / (1 - 2^-q)
/// for an error falling like h^q (q: -error_estimate_order, default 1: the order measured for
/// the clamp ends' singularity at nu 0.49, docs/ACCURACY.md). The stored estimates are
///   rel_l2 = theta ||e||_L2 / ||P u_h + theta e||_L2    (function norms over the body)
///   max_u  = (max|P u_h + theta e| - max|P u_h|) / max|P u_h|   (fine nodes; signed)
///   alpha  = -max_u max|u_h| / (alpha dmax/dalpha)       (signed: the traction for the target)
/// A first try solved the tangent on the new dofs only (the hierarchical estimate, CG + Jacobi):
/// it missed the global, too-stiff part of the error (100x too small on Random2D, docs/ACCURACY.md).
#include <functional>
#include <memory>
#include <vector>

#include <petscpc.h>

#include "hypershape/core/petsc_handle.hpp"
#include "hypershape/mesh/refine.hpp"
#include "hypershape/physics/problem.hpp"

namespace hypershape::solver {

class LocalRelaxation;  // solver/local_relaxation.hpp (Eigen): kept out of this header

struct ErrorEstimate {
  bool ok = false;           ///< false: the estimate could not be formed (values 0)
  /// Not formed because u_h itself has det F <= 0 at a quadrature point of the refined mesh: the
  /// label's field inverts inside a cell, between the points its own solve checked (seen with
  /// the mean-dilatation element under tractions narrower than a cell; docs/ACCURACY.md).
  bool inverted = false;
  double rel_l2 = 0;         ///< relative L2 error of u (function norm)
  double max_u = 0;          ///< relative error of max|u|, signed
  double alpha = 0;          ///< relative error of alpha for the stored target, signed
  double raw_rel_l2 = 0;     ///< ||e|| / ||P u_h + e|| (theta = 1)
  double raw_max_u = 0;      ///< max_u with theta = 1
  double slope = 0;          ///< dmax|u| / dalpha used for the alpha estimate
  int krylov_iterations = 0;
  int relaxations = 0;       ///< fine states relaxed locally before a Newton step (LocalRelaxation)
  bool krylov_budget_spent = false;  ///< a fine step stopped at the Krylov budget (its iterate kept)
  bool newton_steps_converged = false;  ///< one full Newton step, or steps to 1% of the first residual
  int residual_assemblies = 0, tangent_assemblies = 0, factorizations = 0;
  double seconds = 0;
  double seconds_assembly = 0, seconds_linear = 0;  ///< parts of `seconds`: fine residuals and tangents; the fine solves
  /// Rank 0, where formed: P u_h + e, the fine Newton's last state at alpha (canonical node order
  /// of the fine space, n_nodes x dim): a start for the label on the refined mesh.
  std::vector<double> fine_state;
};

/// The exact L2 norm squared of a P1/P2 nodal field (n_comp components, canonical node order)
/// on straight-sided simplices given by `coords` and `cells` (VTK order). Not collective.
double l2_norm_squared(int dim, int degree, const std::vector<double>& coords,
                       const std::vector<std::int64_t>& cells, const std::vector<double>& field, int n_comp);
/// The same for several fields in one pass over the cells (each as l2_norm_squared gives it).
std::vector<double> l2_norms_squared(int dim, int degree, const std::vector<double>& coords,
                                     const std::vector<std::int64_t>& cells,
                                     const std::vector<const std::vector<double>*>& fields, int n_comp);

/// y = K_c^-1 x with a factor of the coarse tangent at (or next to) u_h; false on failure.
/// `refined` false: the two-grid preconditioner's coarse level, where a single-precision factor's
/// own solve is enough (NonlinearSolver::apply_tangent_factor).
using CoarseSolve = std::function<bool(Vec x, Vec y, bool refined)>;

class TwoLevelEstimator {
 public:
  /// `coarse`: the solved problem; `fine`: the same scene on `refined.mesh` (same degree), whose
  /// coarse mesh is the one `coarse` was built from. Builds P. Collective over the problems'
  /// communicator (the same for both). The linear solve reads PETSc options with prefix
  /// "error_estimate_" (-error_estimate_ksp_rtol, -error_estimate_mg_levels_ksp_max_it, ...);
  /// -error_estimate_no_relaxation and -error_estimate_relaxation_seeds N (default 2^dim x
  /// LocalRelaxation::kMaxSeeds) set the local relaxation of the fine states (relax()).
  /// `newton_to_tolerance`: Newton on the fine problem to 1% of its first residual (at most 4
  /// steps) even when the first step is a full one (the mean-dilatation element's estimates
  /// need it); otherwise one full step is the estimate.
  TwoLevelEstimator(const physics::Problem& coarse, const physics::Problem& fine, const mesh::RefinedMesh& refined,
                    bool newton_to_tolerance = false);
  ~TwoLevelEstimator();
  TwoLevelEstimator(const TwoLevelEstimator&) = delete;
  TwoLevelEstimator& operator=(const TwoLevelEstimator&) = delete;

  /// Estimates the error of `u_h` (a global vector of the coarse problem) at load factor
  /// `alpha`; the fine problem must carry the same load case. `coarse_solve`: a factor of the
  /// coarse tangent the caller already holds (NonlinearSolver::apply_tangent_factor), the
  /// two-grid solver's coarse level and du/dalpha; empty: K_c(u_h) is assembled and factorised
  /// here (one assembly and one numeric factorisation more per estimate). Collective. Never
  /// throws for a numerical failure (ok = false); PETSc errors throw core::PetscError.
  ErrorEstimate estimate(Vec u_h, double alpha, const CoarseSolve& coarse_solve = {}) const;

  /// P u: a coarse global vector prolonged into a fine global vector. Collective.
  void prolong(Vec coarse, Vec fine) const;
  /// The same on canonical nodal arrays (rank 0; empty elsewhere). Not collective.
  std::vector<double> prolong(const std::vector<double>& coarse_values) const;
  Mat interpolation() const { return P_.get(); }

 private:
  /// Newton on the fine problem from P u_h (the two-grid solver set up): e = u_fine - P u_h.
  bool fine_newton(Vec Pu, double alpha, Vec e, ErrorEstimate& out) const;
  /// One step of it from x (energy ex, residual r, negated here): the tangent assembled, the step solved by
  /// the two-grid GMRES (fv_[2]), the energy line search (the new state in fv_[3]); at the
  /// `first` step, the preconditioner's own step where the Newton step has no descent
  /// (`fell_back`). The step length, 0 for none, -1 if the assembly or the solve failed; `ew`: the
  /// energy of the new state.
  double fine_step(Vec x, double ex, Vec r, double alpha, bool first, bool& fell_back, double& ew,
                   ErrorEstimate& out) const;
  /// The largest step lambda in {1, 1/2, ..., > 0.03} with E(x + lambda dx) <= E(x) = ex (w: that
  /// state, ew: its energy), or 0. Energy evaluations counted in out.seconds_assembly.
  double energy_search(Vec x, double ex, Vec dx, double alpha, Vec w, double& ew, ErrorEstimate& out) const;
  /// Relaxes x on the patch where the fine residual r sits (LocalRelaxation; one rank,
  /// conservative problems), then its energy ex, r and |r| = rn anew; false where nothing moved.
  bool relax(Vec x, double alpha, Vec r, double& ex, PetscReal& rn, ErrorEstimate& out) const;
  /// The coarse level: y = K_c^-1 x by `coarse_` (the caller's factor) or by `direct_`.
  void coarse_apply(Vec x, Vec y, bool refined) const;
  static PetscErrorCode apply_coarse(PC pc, Vec x, Vec y);
  /// Sets up the coarse solve of one estimate (the caller's factor, or K_c(u_h) factorised).
  bool prepare_coarse(Vec u_h, const CoarseSolve& coarse_solve, ErrorEstimate& out) const;
  const physics::Problem& coarse_;
  const physics::Problem& fine_;
  bool newton_to_tolerance_ = false;
  /// Prolongation in canonical numbering (every rank): fine node i = sum_k w[k] coarse node
  /// col[k], k in [row[i], row[i+1]).
  std::vector<std::int64_t> row_, col_;
  std::vector<double> w_;
  core::MatH P_;                 ///< the same in global dofs (constrained dofs dropped)
  mutable core::MatH Kf_, Kc_;  ///< fine and coarse tangents, allocated at the first estimate
  /// The two-grid solver, kept (its coarse level a PC shell: apply_coarse).
  mutable core::KSPH ksp_;
  /// Without a caller's factor: the direct solver of K_c(u_h), kept (the symbolic phase once
  /// per shape, a numeric refactorisation per estimate).
  mutable core::KSPH direct_;
  mutable CoarseSolve coarse_solve_;  ///< the caller's factor during one estimate
  mutable bool coarse_failed_ = false;
  /// Work vectors (fine: x, r, dx, w, g, P u_h, e; coarse: du/dalpha), made at the first estimate.
  mutable std::vector<core::VecH> fv_;
  mutable core::VecH du_dalpha_;
  mutable std::unique_ptr<LocalRelaxation> relaxation_;  ///< relax()'s, made at its first use
  mutable core::VecH no_fixed_;                           ///< zero: no dof held in the relaxation
};

}  // namespace hypershape::solver
