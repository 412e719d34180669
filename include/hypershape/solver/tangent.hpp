#pragma once
/// The tangent of a Problem and the factorisations kept for it: the piece of the nonlinear
/// solver that owns every linear solve of the displacement-controlled path.
///
/// Newton-Krylov on a kept factorisation. A Newton step needs K(u) x = b with K(u) the tangent
/// at the current iterate. Factorising K(u) at every iterate (a direct Newton) is what made a
/// load case cost 11-17 numeric factorisations. Here K(u) is assembled (cheap: a cell loop)
/// and x found by GMRES on K(u), right-preconditioned by the LDL^T factor of a tangent K(u_f)
/// at an earlier state u_f. Near u_f the preconditioned operator is close to the identity and
/// GMRES converges in a few iterations, each one triangular solve and one sparse product.
///
/// Refresh ("rent or buy"): one factorisation costs as much as `budget` Krylov iterations
/// (measured: a triangular solve is ~1/25 of a numeric factorisation in 2D at a few thousand
/// unknowns, 1/30-1/100 and more in 3D). A new factorisation of the current K(u) is bought when
/// the Krylov iterations spent since the last one reach the budget, or when a solve does not
/// converge within what is left of it. Both rules count iterations, never seconds: the
/// sequence of factorisations, and so the data, is the same on every run.
///
/// Slots: the factor in use is either the work factor (refreshed as above) or the factor of K(0)
/// (the state every load case starts from; dead loads, so the same for every load case of the
/// problem), made once per problem and kept: in 2D, and in 3D where the factors are single
/// precision (TangentOptions::single_factor; two single factors take the memory of one double).
/// A 3D double factor is not doubled (hundreds of MiB per rank at the 3D presets' sizes for one
/// factorisation in about fifteen per load case): a load case factorises K(0) anew.
///
/// Counters (numeric and symbolic factorisations, Krylov iterations, tangent assemblies) are
/// counted where they happen; log events make -log_view show the split.
///
/// A problem with a follower load (physics::Problem::conservative() false) has a non-symmetric
/// tangent K: it is factorised by LU (PETSc's own in 2D on one rank, MUMPS otherwise), no factor
/// of K(0) is kept (a fixed follower load drawn per load case changes it), and the multigrid
/// kind is not available. An LU factor has no inertia; the stability check there is that the
/// symmetric part (K + K^T)/2 is positive definite, by the inertia of its LDL^T factor (one more
/// factorisation, counted): a sufficient condition for stability (for every real v, v.K v =
/// v.(K + K^T)/2 v > 0, so every eigenvalue of K has a positive real part and no divergence
/// mode exists), not a necessary one. negative_eigenvalues() then counts the negative
/// eigenvalues of (K + K^T)/2.
#include <petscksp.h>

#include <cstdint>
#include <memory>
#include <string>

#include "hypershape/core/petsc_handle.hpp"
#include "hypershape/physics/problem.hpp"
#include "hypershape/solver/ldlt.hpp"
#include "hypershape/solver/multigrid.hpp"

namespace hypershape::solver {

/// Linear-algebra work of a solve, counted where it happens.
struct LinearCounters {
  std::int64_t numeric_factorizations = 0;
  std::int64_t symbolic_factorizations = 0;
  std::int64_t krylov_iterations = 0;
  std::int64_t tangent_assemblies = 0;
  /// Solves with U^T |D| U instead of the factor itself (the corrector's modified Newton steps,
  /// solver.absolute_pivots): each is a pair of triangular solves, no factorisation.
  std::int64_t modified_solves = 0;
  LinearCounters& operator+=(const LinearCounters& o);
  LinearCounters operator-(const LinearCounters& o) const;
};

struct TangentOptions {
  /// Newton-Krylov on a kept factorisation. false (default): a direct solve with a fresh
  /// factorisation of every assembled tangent. Measured side by side (scripts/bench_versions.sh):
  /// 2.3-2.7x fewer numeric factorisations, but no fewer seconds on Random2D (P1 h 0.04) nor on
  /// Random3D (P2 mesh.h 0.2): with a nearly incompressible material the tangent turns with the
  /// body, a factor of an earlier state preconditions it poorly (5-9 GMRES iterations per solve),
  /// and the back-solves cost what the factorisations saved.
  bool reuse = false;
  /// Krylov iterations a factorisation may cost before the current tangent is factorised anew
  /// (0: by dimension, 2D 25, 3D 60; measured with bench_solver and scripts/bench_generate.sh).
  int krylov_budget = 0;
  /// Relative tolerance of each Krylov solve (the inexact Newton forcing term).
  double krylov_rtol = 1e-3;
  /// The linear solver of the tangent (multigrid.hpp). `automatic`: AMG (gamg) for 3D problems
  /// of at least `auto_dofs` unknowns, the direct LDL^T otherwise.
  LinearSolver linear = LinearSolver::automatic;
  std::int64_t auto_dofs = 150000;
  /// The factorisation in single precision, its solves refined to double (single_factor.hpp;
  /// config `solver: {factor_precision: single}`): symmetric tangents on one rank only (a solver
  /// group and an LU factor keep double). The answers agree with double's to the Newton tolerance,
  /// not bit for bit.
  bool single_factor = false;
};

class Tangent {
 public:
  /// Collective over the problem's communicator. `prefix`: options prefix of the factor KSPs
  /// (as the SNES's, so -pc_factor_mat_solver_type etc. apply).
  Tangent(const physics::Problem& problem, const TangentOptions& opt, const std::string& prefix);
  Tangent(const Tangent&) = delete;
  Tangent& operator=(const Tangent&) = delete;

  /// K(u) at load factor `s` (which matters only for a scaled follower load) into matrix() (not
  /// factorised). False (every rank) if det F <= 0 somewhere. Collective.
  bool assemble(Vec u, double s = 0.0);
  /// Shifts the assembled tangent: K + mu I (inertia-corrected Newton). Collective.
  void shift(double mu);
  /// Factorises the assembled tangent into the work factor, which becomes the one in use.
  /// False if the factorisation failed. Collective.
  bool factorise();
  /// 2D: makes the factor of K(0) the one in use (assembled at `rest` and factorised on the first
  /// call only). 3D: nothing; returns false. Collective.
  bool use_rest_factor(Vec rest);
  /// Solves K(u) x = b for the assembled tangent (x: initial guess if `guess`). Reuse: GMRES
  /// preconditioned by the factor in use, refreshed by the budget rule; otherwise a fresh
  /// factorisation and a direct solve. False if no solve succeeded. Collective.
  bool solve(Vec b, Vec x, bool guess);
  /// solve(b1, x1, guess1) then solve(b2, x2, false), the same numbers; a direct solver's
  /// factor is read once for both. x1, x2 must not alias b2, b1. `absolute`
  /// (absolute_solves()): with the factor's D replaced by |D| (LdltFactor::solve_pair). Collective.
  bool solve_pair(Vec b1, Vec x1, bool guess1, Vec b2, Vec x2, bool absolute = false);
  /// Whether the factor in use can solve with |D| (a direct 2D blocked factor, no multigrid, no reuse).
  bool absolute_solves() const { return !multigrid() && !opt_.reuse && has_factor() && factor().has_absolute(); }
  /// Applies the inverse of the factor in use: y = F^-1 x (no Krylov). Collective.
  bool apply_factor(Vec x, Vec y, bool refined = true);
  /// Inertia of the factor in use; -1 unknown. Exact for K(u) only if factor_is_current().
  /// Non-symmetric K (LU): the negative eigenvalues of (K + K^T)/2 when the factor in use is of
  /// the assembled K (its LDL^T made on the first call after the factorisation), else -1. The path
  /// takes it at its final state only (stability()): one LDL^T per target solve.
  int negative_eigenvalues();
  /// The tangent is factorised by LU (a follower load), not by LDL^T.
  bool lu() const { return !problem_.conservative(); }
  /// Multigrid kind: whether the assembled tangent is positive definite, for the stability
  /// check of a converged state without its factorisation: LOBPCG preconditioned by the AMG
  /// from `start` (overwritten), and, where that does not settle the sign, a factorisation.
  /// Returns 0 (positive definite), >= 1 (indefinite; exact count only if factorised) or -1
  /// (the factorisation failed). LU kind: the negative eigenvalues of (K + K^T)/2 of the assembled
  /// K (its LDL^T; `start` unused). Collective.
  int stability(Vec start);
  /// The tangent is solved by AMG-preconditioned Krylov (not by a factorisation).
  bool multigrid() const { return linear_ == LinearSolver::gamg || linear_ == LinearSolver::hypre; }
  LinearSolver linear_solver() const { return linear_; }
  /// The factor in use is of the assembled tangent (no assembly since the factorisation).
  bool factor_is_current() const { return current_; }
  /// A factor is in use (none before the first factorisation).
  bool has_factor() const { return use_rest_ || work_->factored(); }
  Mat matrix() const { return J_.get(); }
  const LinearCounters& counters() const { return n_; }
  const TangentOptions& options() const { return opt_; }
  /// The relative tolerance of the next Krylov solves (the inexact Newton forcing term).
  void set_forcing(double rtol) { forcing_ = rtol; }

 private:
  LdltFactor& factor() const { return use_rest_ ? *rest_ : *work_; }
  /// LU kind: the negative eigenvalues of (K + K^T)/2 of the assembled K (LDL^T of S_).
  int symmetric_part_inertia();
  bool krylov_solve(Vec b, Vec x, bool guess, int max_its, bool& converged);
  /// Multigrid kind: the AMG of the assembled tangent, set up once per assembly.
  void set_up_multigrid();
  /// Multigrid kind: CG + AMG to the forcing term; a factorisation of this tangent where the
  /// Krylov solve fails (an indefinite tangent near a limit point; counted as such).
  bool multigrid_solve(Vec b, Vec x, bool guess);
  /// One Krylov solve of `ksp` to the forcing term relative to ||b|| (also with a guess),
  /// its iterations counted; returns PETSc's reason.
  KSPConvergedReason run_krylov(KSP ksp, Vec b, Vec x, bool guess, int max_its, PetscInt& its);
  static PetscErrorCode apply_shell(PC pc, Vec x, Vec y);

  const physics::Problem& problem_;
  TangentOptions opt_;
  std::string prefix_;
  core::MatH J_;        ///< the assembled tangent K(u) (the Krylov operator)
  core::MatH J0_;       ///< K(0), 2D
  std::unique_ptr<LdltFactor> work_, rest_;  ///< of the current tangent at factorise(); of K(0)
  // LU kind: (K + K^T)/2, K^T, the LDL^T of the former and its count (-2: not yet for this K).
  core::MatH S_, Kt_;
  std::unique_ptr<LdltFactor> symmetric_part_;
  int symmetric_negative_ = -2;
  core::KSPH krylov_;   ///< GMRES on J_, right-preconditioned by the factor in use (PC shell)
  LinearSolver linear_ = LinearSolver::direct;  ///< resolved (never automatic)
  core::KSPH amg_;      ///< multigrid kind: CG + AMG on J_
  bool amg_current_ = false;  ///< amg_'s preconditioner is of the assembled tangent
  bool use_rest_ = false;
  bool current_ = false;
  double forcing_ = 1e-3;
  int since_factor_ = 0;  ///< Krylov iterations spent on the factor in use
  LinearCounters n_;
};

}  // namespace hypershape::solver
