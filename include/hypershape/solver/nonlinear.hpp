#pragma once
/// Nonlinear solves of one Problem: one SNES (and so one matrix, one KSP and one symbolic
/// factorisation) kept for all its load cases.
///
/// Its pieces, one file each (src/solver/): nonlinear.cpp (set-up, the SNES callbacks, the guarded
/// line search, solve_for_target), load_control.cpp (Newton at a given load, continuation, the
/// alpha search of control: load), path_following.cpp (displacement control: predictor,
/// corrector, the final check), branch_switch.cpp (the tangent's modes, energy minimisation); the
/// tangent, its factors and Krylov solves in tangent.hpp. Each registers PETSc log events
/// (HSLoadControl, HSPredictor, HSCorrector, HSBranchSwitch, HSTangentAsm, HSFactor, ...), so
/// -log_view splits a load case by piece.
///
/// Defaults (each overridable in the PETSc options database, prefix "" unless given):
///   -snes_type newtonls with our guarded line search (type shell): a trial state with
///   det F <= 0 has energy +inf and is never accepted (the "guard"); an admissible one is taken
///   on Armijo decrease of the potential energy, or of the residual norm where the tangent is
///   indefinite or the energy change is below round-off. (PETSc 3.18's bt with an objective
///   models 1/2 obj with the full slope and stalls on indefinite tangents: measured here.)
///   -ksp_type preonly -pc_type cholesky (the Neo-Hookean tangent is symmetric; LDL^T was 1.6x
///   faster than LU here) with -pc_factor_mat_solver_type petsc -pc_factor_mat_ordering_type
///   qmd in 2D on one rank (PETSc's own LDL^T: 1.4x faster per load case than MUMPS on
///   Random2D shapes of ~4500 unknowns, whose per-call overhead dominates there), mumps in 3D
///   (where PETSc's non-supernodal factorisation is far slower) and on solver groups of
///   several ranks;
///   -snes_stol 0 (a small step is not convergence: the residual must be small).
/// Load continuation (solve): if a step fails, return to the last converged state and halve
/// the increment; after a success, double it.
///
/// Target displacement (solve_for_target), by default by displacement control: the unknowns
/// are (u, alpha), with the constraint max|u| = d added to equilibrium (a bordered Newton
/// system solved with the tangent's one factorisation and two back-substitutions: K a = f_ext,
/// K b = R), and d continued from the current max|u| to the target in adaptive increments:
///   - predictor: the tangent step to max|u| = d_next, damped by the guarded line search;
///   - corrector: bordered Newton; the u-part of each step is Newton's step at the load
///     alpha + dalpha and goes through the same guarded energy line search (never a state with
///     det F <= 0), alpha moving by the same fraction; intermediate increments are converged
///     to path_rtol only, the last to rtol, with Chebyshev's step there (Newton's plus its
///     second-order term; SolverOptions::corrector);
///   - an increment that fails (max_newton iterations, no progress after 4, Newton creeping:
///     three steps cut below 0.3 by the line search without halving |R|, or, with
///     abandon_off_path, an iterate that left the path: off_the_path) is discarded,
///     the state restored and the increment halved; after an easy success (<= 2 iterations) it
///     doubles, after a hard one (>= 6) it halves (FEBio-style); an intermediate increment
///     takes at least one corrector iteration (the next predictor needs its tangent);
///   - the first increment from rest is the previous load case's first; max_halvings failures
///     in a row, or increments below 1e-3 of the way, end the path; limit points of the load
///     are passed (alpha may fall);
///   - stability: LDL^T gives the inertia of every tangent (negative pivots = negative
///     eigenvalues, negative_eigenvalues()); a final state whose tangent is indefinite is an
///     unstable equilibrium ("loss of stability") and is never returned as converged;
///   - branch switching (branch_switches times) after a path that ended unstable or stalled:
///     see switch_branch(); measured on 1000 Random2D load cases: 98.7% -> 99.9% converged;
///   - a budget of newton_budget iterations per target solve (switches included) bounds the
///     cost of a failure;
///   - optionally (arc_length_rescue, off by default) an arc-length rescue where the path and its
///     switches failed (not at a verified fold): the load case again from rest by arc_path(),
///     with a budget of its own;
///   - a retry from rest without the first-increment hint (retry_from_rest) where all that failed
///     on a path that started from the hint.
/// Measured on 2 Random2D shapes x 20 load cases (P1, h 0.04): 18-25 Newton iterations per load
/// case against 73-103 for the former strategy (control: load: load-controlled solves at
/// secant-updated alpha), which stays available, as does a load-control fallback after a
/// failed path (fallback: true; it rescued none of the failures there at twice their cost).
#include <petscsnes.h>

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "hypershape/core/petsc_handle.hpp"
#include "hypershape/physics/problem.hpp"
#include "hypershape/solver/local_relaxation.hpp"
#include "hypershape/solver/tangent.hpp"

namespace hypershape::solver {

class CreepWatch;  // step_control.hpp

/// How solve_for_target reaches its target max|u|.
enum class Control {
  displacement,  ///< path-following in d = max|u| with alpha as an unknown (default)
  load,          ///< load-controlled solves at secant-updated alpha (the former default)
};

/// The displacement-controlled path's predictor (SolverOptions::predictor).
enum class Predictor {
  tangent,       ///< the tangent step to the next max|u| (the only one until 2026-11-29)
  second_order,  ///< the tangent step plus the path's second-order term where it is small
};

/// The displacement-controlled path's corrector step in its last increment (SolverOptions::corrector).
enum class Corrector {
  newton,     ///< Newton's (bordered) step (the only one until 2026-11-29)
  chebyshev,  ///< Newton's step plus its second-order term where that is small (Chebyshev's method)
};

struct SolverOptions {
  double rtol = 1e-9;          ///< converged when ||R|| <= rtol ||alpha f_ext|| (+ atol)
  double atol = 1e-12;
  Control control = Control::displacement;
  double path_rtol = 0.3;      ///< displacement control: rtol of intermediate increments
  int newton_budget = 200;     ///< Newton iterations per solve / target solve (then: failure)
  bool fallback = false;       ///< displacement control failed: try load control from there
  int branch_switches = 3;     ///< displacement control failed: leave the branch this often
  int max_halvings = 6;        ///< displacement control: failed increments in a row (then: fail)
  int max_newton = 12;         ///< Newton iterations per increment (then: smaller increment)
  /// Displacement control: an increment whose corrector took <= 2 iterations is followed by one
  /// this many times longer (next_step). 0: by dimension (step_growth(): 1.5 in 2D since
  /// 2026-11-27, 2 before; 2 in 3D).
  double step_growth = 0;
  /// Displacement control: abandon an intermediate increment at its first iterate that leaves
  /// the path (off_the_path) instead of letting Newton creep there. Off by default: it saves a
  /// tenth of the Newton iterations of Random2D P2 paths, but loses load cases at bifurcations.
  bool abandon_off_path = false;
  /// Displacement control: where the line search cut an intermediate iterate's Newton step below
  /// 0.3 at an indefinite tangent, step once more with U^T |D| U (absolute_pivots(); 2D blocked
  /// factors). Off by default: every load case with a stable state on its path converged on three
  /// unseen seeds (1000 / 998 / 998 against 999 / 998 / 998) for 1-2% more Newton iterations
  /// (docs/STABILITY.md, "Modified Newton"). Also set by the PETSc option -path_absolute_pivots.
  bool absolute_pivots = false;
  /// Displacement control failed and the branch switches did not help (not at a verified fold):
  /// follow the path once more from rest by arc-length continuation (the constraint on the step
  /// along the path's own direction instead of on max|u|), which passes the points where max|u|
  /// itself stops growing along the path, and reach the target under displacement control from
  /// where max|u| crosses it. A budget of newton_budget iterations of its own. Only load cases
  /// that failed before it ran change (measured: 3000 Random2D load cases of unseen seeds, every
  /// other array bit for bit; docs/STABILITY.md, "Seeds nobody tuned on"). In 2D only: on the random3d
  /// preset (seed 90210, 200 load cases) it rescued none (0 of 1) for 5% more Newton iterations.
  /// Off by default since 2026-11-28: the two load cases it was measured to rescue are solved
  /// without it (777/11/20 by the branch switches, 31337/13/10 by the retry from rest, at the same
  /// equilibrium), and on 14 000 load cases of four 2D presets (five unseen seeds of Random2D at
  /// P1 and P2, two of OODRandom2D and EasyRandom2D) no load case needed it: of the 32 it ran on
  /// it brought one to the target (31337/13/10), which the retry from rest reaches without it.
  /// It cost 3.8% of all Newton iterations at P2 (0.6% at P1); every label is the same without it
  /// (docs/STABILITY.md, "The arc-length rescue, off by default").
  bool arc_length_rescue = false;
  /// Displacement control failed (after the switches and the rescue; not at a verified fold) on
  /// a path whose first increment was the previous load case's (the hint): solve it once more from
  /// rest without the hint, with a budget of its own, as a load case solved alone would be.
  /// The next load case's hint stays the one the first try left, so load cases that converged
  /// are unchanged bit for bit (docs/SOLVER.md, "a retry from rest").
  bool retry_from_rest = true;
  /// The data factory, 2D P2 only: a load case that failed after all of the above (not at a
  /// verified fold) is solved with P1 elements on the same mesh, and the P2 path taken once more
  /// from that state (factory/p1_start.hpp). Only load cases that failed change.
  bool p1_start = true;
  /// Displacement control: the increment's predictor. `second_order` (default since 2026-11-29)
  /// adds the path's second-order term to the tangent step v = dalpha K^-1 f_ext:
  /// -K^-1 q with q = (R(u + v, s + dalpha) + R(u - v, s - dalpha)) / 2 - R(u, s), two residuals and
  /// a solve with the factor at hand (NonlinearSolver::second_order_term), where that term is at
  /// most a tenth of v (|.|_inf); `tangent`: the tangent step alone (before). docs/SOLVER.md.
  Predictor predictor = Predictor::second_order;
  /// Displacement control: the corrector's step in the last increment (converged to rtol; the
  /// intermediate ones, converged to path_rtol only, take Newton's). `chebyshev` (default since
  /// 2026-11-29) adds to Newton's step delta its second-order term -K^-1 q, q = (R(u + delta) +
  /// R(u - delta)) / 2 - R(u) (Chebyshev's method: the error falls with its cube near a solution),
  /// where that term is at most delta (|.|_inf): two residuals and a solve with the factor at hand
  /// per iteration (NonlinearSolver::chebyshev_step). `newton`: Newton's step alone (before).
  /// docs/SOLVER.md, "corrector".
  Corrector corrector = Corrector::chebyshev;
  /// Nonlinear elimination: before each corrector step, where the residual sits on a few nodes,
  /// relax them on their patch first (LocalRelaxation).
  bool local_relaxation = true;
  /// The displacement-controlled path's linear solves: Newton-Krylov on a kept factorisation
  /// (default) or a fresh factorisation per Newton iteration (tangent.reuse = false).
  TangentOptions tangent;
  int max_increments = 64;     ///< continuation increments per solve
  double min_increment = 1e-4; ///< smallest increment, relative to the requested change
  bool guard = true;           ///< energy objective + bt line search (else: full Newton steps)
  double target_rtol = 1e-3;   ///< alpha search: |max|u| / target - 1| <= target_rtol
  int max_target_solves = 30;
};

/// Outcome of one solve: data, never an exception.
struct SolveResult {
  bool converged = false;
  std::string reason;          ///< PETSc's converged reason of the last SNES solve, or ours
  int newton_iterations = 0;   ///< total over increments (failed ones included)
  int linear_solves = 0;
  int increments = 0;          ///< successful increments
  int failed_increments = 0;
  double load_factor = 0;      ///< reached load factor (= requested if converged)
  double residual_norm = 0;
  double max_displacement = 0;
};

struct TargetResult {
  bool converged = false;
  std::string reason;
  double alpha = 0;
  double max_displacement = 0;
  int solves = 0;              ///< nonlinear solves (alpha evaluations)
  int newton_iterations = 0;
  int failed_increments = 0;
  int increments = 0;              ///< accepted increments (displacement control)
  int recovery_iterations = 0;     ///< Newton iterations spent in failed (discarded) increments
  int off_path_increments = 0;     ///< of the failed ones: abandoned off the path (off_the_path)
  LinearCounters linear;           ///< factorisations, Krylov iterations, assemblies of this solve
  int negative_pivots = -1;        ///< of the last tangent factorisation (MUMPS LDL^T; -1: unknown)
  double seconds_first_solve = 0;  ///< linear response + the first nonlinear solve
  double seconds_total = 0;
  /// Adds the counts of an earlier attempt of the same target solve (a path before a branch
  /// switch, a rescue or a fallback): all its Newton iterations count as recovery where it was
  /// discarded as a whole (`discarded`), else its own recovery does.
  void add_earlier(const TargetResult& e, bool discarded) {
    solves += e.solves;
    newton_iterations += e.newton_iterations;
    failed_increments += e.failed_increments;
    off_path_increments += e.off_path_increments;
    increments += e.increments;
    recovery_iterations += discarded ? e.newton_iterations : e.recovery_iterations;
  }
  /// add_earlier(e, true) for an attempt solved apart from this one (its own target solve, whose
  /// linear counts and seconds this one's do not include): those are added too.
  void add_discarded_solve(const TargetResult& e) {
    add_earlier(e, true);
    linear += e.linear;
    seconds_total += e.seconds_total;
  }
};

/// Puts config-file PETSc options (name with dash, value or "") into the options database,
/// except those already given (on the command line, which wins). Not collective.
void set_default_options(const std::vector<std::pair<std::string, std::string>>& options);

/// Where a displacement-like vector v of `problem` (a mode of the tangent) lives: `nodes`, the
/// nodes whose |v_i|^2 exceeds a tenth of the largest, and `at`, the reference coordinates of the
/// largest (ties: the smallest canonical node id), the same on any rank count. A handful of
/// nodes is a local instability (an element-scale crease), hundreds or more a global one (the
/// body buckling). Collective.
struct ModeExtent {
  long nodes = 0;
  std::array<double, 3> at{};
};
ModeExtent mode_extent(const physics::Problem& problem, Vec v);

/// Whether a failed target solve's reason is a verified fold (follow_path: the state on target
/// is on an unstable segment between limit points of the load), which neither the arc-length
/// rescue, a retry from rest nor a start from another discretisation's state gets past.
bool verified_fold(const std::string& reason);

class NonlinearSolver {
 public:
  /// Collective over the problem's communicator; reads PETSc options with `prefix`.
  NonlinearSolver(const physics::Problem& problem, const SolverOptions& opt = {},
                  const std::string& prefix = "");
  NonlinearSolver(const NonlinearSolver&) = delete;
  NonlinearSolver& operator=(const NonlinearSolver&) = delete;

  /// The current (last converged) displacement, a global vector.
  Vec solution() const { return u_.get(); }
  double load_factor() const { return s_; }
  /// Back to u = 0 at load factor 0 (the first-increment hint is kept: the next load case of a
  /// shape starts from the last one's first increment, as in the factory).
  void reset();
  /// That hint (0: none). A timing study sets it back before repeating a load case, so that every
  /// repeat solves as the first did (a load case hinted by its own first increment skips the
  /// failed first tries the first run paid: not the factory's cost).
  double step_hint() const { return step_hint_; }
  void set_step_hint(double hint) { step_hint_ = hint; }
  /// solve_for_target() from the state u (a global vector of the problem, e.g. another
  /// discretisation's solution) at load factor s instead of from rest: the path continues from
  /// there, then the branch switches as after any path (no retry from rest). The next load
  /// case's first-increment hint is left as it was. Collective.
  TargetResult solve_for_target_from(Vec u, double load_factor, double target);
  /// Solves R(u) = f_int(u) - s f_ext = 0 at load factor `s`, continuing from the current state.
  SolveResult solve(double load_factor);
  /// Finds alpha with |max|u| / target - 1| <= target_rtol, reusing the state, matrix and
  /// factorisation structure between evaluations.
  TargetResult solve_for_target(double target);
  /// max|u| of the linear response to the nominal load at the current state (one linear solve).
  double linear_response();
  /// The linear response du = K(u)^-1 f_ext at the current state u (the tangent assembled into
  /// jacobian_matrix() and solved on the SNES's KSP, which keeps the solve's converged reason),
  /// in `du` (a vector of the problem); returns max|du|, or nothing if the tangent cannot be
  /// formed at u. Collective.
  std::optional<double> linear_response(Vec du);

  /// y = F^-1 x with the tangent factor the last solve left in use (of the tangent at, or one
  /// Newton step before, its final state). False where none exists (the multigrid linear
  /// solver; no path followed yet: solve() runs on the SNES's own solver) or the solve fails. The labels' error estimate uses it as its coarse solve.
  /// `refined` false: inside a preconditioner (a single-precision factor's solve not refined).
  /// Collective.
  bool apply_tangent_factor(Vec x, Vec y, bool refined = true);

  SNES snes() const { return snes_.get(); }
  Mat jacobian_matrix() const { return J_.get(); }
  const physics::Problem& problem() const { return problem_; }

 public:
  struct LoadExtremes;  ///< the load's extremes along a path (path_following.cpp)

 private:
  /// t with its seconds (from `start`) and the linear solver's counts since `linear_before`.
  TargetResult timed(TargetResult t, double start, const LinearCounters& linear_before) const;
  static PetscErrorCode form_function(SNES, Vec, Vec, void*);
  static PetscErrorCode form_jacobian(SNES, Vec, Mat, Mat, void*);
  static PetscErrorCode form_objective(SNES, Vec, PetscReal*, void*);
  static PetscErrorCode guarded_line_search(SNESLineSearch, void*);
  void line_search(SNESLineSearch ls);
  /// The guarded line search on W = X - lambda Y at load factor s, F = R(X, s): returns the
  /// accepted lambda (G = R(W, s)) or 0.
  double backtrack(Vec X, Vec Y, Vec F, double s, Vec W, Vec G);
  /// X = W, the trial backtrack accepted last: its stored energy is kept for X's next line
  /// search (its energy at lambda = 0 without a pass over the cells).
  void accept_trial(Vec W, Vec X);
  /// Keeps the trial evaluated last (its energy and internal force) as X's.
  void keep_trial_as(Vec X);
  /// The energy of X at load s: from the stored energy accept_trial kept if X is unchanged since.
  double energy_at_start(Vec X, double s);
  /// R(X, s) into r, from the internal force accept_trial kept if X is unchanged since. False
  /// where X is inadmissible.
  bool residual_at(Vec X, double s, Vec r);
  /// Whether X is bit for bit the state accept_trial kept the stored energy and force of.
  bool is_known_state(Vec X);
  /// Drops the kept energies and forces (known and ahead): the problem may have changed.
  void forget_evaluations();
  /// R(X, s) into r with X's energy and internal force in one pass, kept as accept_trial keeps
  /// a trial's (a conservative problem): X's next residual_at and energy_at_start cost no pass.
  /// False where X is inadmissible.
  bool evaluate_known(Vec X, double s, Vec r);
  /// R(X, s) into r for a state the next line search may try first (u + v of the second-order
  /// terms): with a conservative problem its energy and internal force are kept for it.
  bool evaluate_ahead(Vec X, double s, Vec r);
  /// backtrack's trial W at load s: its energy e and residual G, from evaluate_ahead's pass
  /// where W is bit for bit that state. False where W is inadmissible.
  bool evaluate_trial(Vec W, double s, double& e, Vec G);
  /// Newton's method on the SNES at load factor s from u_, converged when |R| <= atol + rtol (|s|
  /// |f_ext| + fixed_norm) (checked on the true residual; rtol <= 0: the options' rtol).
  bool newton(double s, SolveResult& r, double fixed_norm = 0, double rtol = 0);
  /// With fixed loads (has_fixed_load) and u_ = 0, s_ = 0: the path's start (u = 0 is not an
  /// equilibrium). Newton to the equilibrium under the fixed loads alone (on failure u_ = 0 again:
  /// the path starts from rest), then load steps (alpha doubling) while max|u| falls as alpha
  /// grows, so that displacement control leads alpha up. Adds the iterations to `its`. True if
  /// a_ and negative_pivots_ are the tangent response of the state it leaves.
  bool start_under_fixed_loads(double target, int& its);
  /// A load-controlled step of the path's start from the state in u_/s_ to s_ + step (halved up
  /// to three times where Newton fails), converged to path_rtol of |s f_ext| + fixed_norm. False
  /// (u_, s_ unchanged) if none converged.
  bool load_step(double step, double fixed_norm, int& its);
  TargetResult search_target(double target, double start);
  /// Displacement control from the current state to max|u| = target; `spent`: Newton
  /// iterations the target solve spent before (counted against newton_budget).
  TargetResult follow_path(double target, double start, int spent = 0);
  /// Where a path starts: the current state; rest, giving up at its first failed increment (a
  /// problem with fixed loads tries that first); the fixed loads' equilibrium
  /// (start_under_fixed_loads).
  enum class PathStart { here, rest_once, fixed_loads };
  /// follow_path's increments from the start `how`.
  TargetResult path(double target, double start, int spent, PathStart how);
  /// The arc-length rescue (SolverOptions::arc_length_rescue): from rest, increments of fixed
  /// length along the path's direction (the tangent at rest, then the secant of the last
  /// increment) until max|u| passes `target`, then path() from there back to it.
  TargetResult arc_path(double target, double start);
  /// arc_path's start: u_ = 0, s_ = 0, a_ = K(0)^-1 f_ext, arc_dir_ = a_ / |a_|_2; returns
  /// |a_|_2 / max|a_| (0 where the response at rest cannot be formed).
  double arc_start();
  /// Back to the state an increment started from (backup_, a0_) at load factor s.
  void restore_increment(double s);
  /// The constraint of the current increment: with arc_ the fixed direction arc_dir_ in c and
  /// c . u - arc_offset_; else control_direction (max|u|). Collective.
  double constraint(Vec u, Vec fallback, Vec c);
  /// The path's first increment from max|u| = d towards `target` (`fresh`: a load case's start).
  double first_step(double target, double d, bool fresh) const;
  /// After the last increment reached `d` = target: checks the state's own tangent; true (with
  /// t.reason: a fold or a loss of stability) if it is not positive definite.
  bool unstable_on_target(double d, const LoadExtremes& extremes, TargetResult& t);
  /// One increment of the path from the equilibrium in u_/s_ to max|u| = d_next: the tangent
  /// predictor (a_ holds K^-1 f_ext there) and the corrector, to rtol if `last`, else path_rtol.
  bool increment(double d_next, bool last, int& its, std::string& why);
  /// The tangent predictor of an increment: from the equilibrium in u_/s_ (a_ = K^-1 f_ext there)
  /// towards max|u| = d_next, damped by the guarded line search. False (`why`) where max|u| does
  /// not respond to the load.
  bool predict(double d_next, std::string& why);
  /// With the tangent step -du_ = dalpha a_ to c . u = m + dalpha c . a_ from the equilibrium u_
  /// at s_: adds the path's second-order term to it (keeping c . step) and to `s_pred`, where
  /// that term is at most a tenth of the step (|.|_inf). False (du_, s_pred unchanged) where it
  /// is larger, u_ -+ the step is inadmissible or the factor's solve fails. Collective.
  bool second_order_term(double dalpha, double ca, double& s_pred);
  /// The second-order term of R along the step v = -du_ from u_: K^-1 q into curvature_, with
  /// q = (R(u_ + v, s + ds) + R(u_ - v, s - ds)) / 2 - R(u_, s) = D^2 R[v, v] / 2 + O(|v|^4) (the
  /// load terms cancel), `q` a scratch vector. Returns |K^-1 q|_inf / |v|_inf, or a negative value
  /// where u_ -+ v is inadmissible or the factor's solve fails (with the factor at hand, unrefined
  /// where it is single precision). Collective.
  double curvature_along_step(double s, double ds, Vec q);
  /// Adds the term curvature_along_step left, -K^-1 q, to the step -du_, with the multiple of
  /// a_ (= K^-1 f_ext) that keeps c . step; returns that multiple (the load's change). Collective.
  double add_curvature_term(double ca);
  /// Whether the corrector converging to `rtol` takes Chebyshev's step (SolverOptions::corrector:
  /// in the last increment, with a direct factor at hand).
  bool chebyshev_corrector(double rtol) const;
  /// The corrector's step -du_ (Newton's, at the load s) plus its second-order term where that is
  /// at most as long; `r` holds R(u_, s) and is moved to the load s + the returned change.
  double chebyshev_step(double s, double ca, Vec r);
  /// The path's result from the state it ended in (`at_target`: its last increment reached
  /// the target): max|u|, alpha, inertia, and the converged state's final check.
  void finish_path(TargetResult& t, bool at_target);
  /// One corrector: Newton on (u, alpha) for max|u| = d from the
  /// current iterate in u_/s_; returns false with `why` set on failure. Leaves in `a_` the
  /// tangent response K^-1 f_ext of its last factorisation (the next predictor).
  bool correct(double d, double rtol, int& its, std::string& why);
  /// Whether the corrector gives up before its iteration k (|R| = rn now, rn0 at its start;
  /// `its` spent of the load case's budget): max_newton reached, no progress after 4, creeping,
  /// or the budget spent; `why` says which.
  bool gives_up(int k, double rn, double rn0, const CreepWatch& creep, int its, std::string& why) const;
  /// SolverOptions::local_relaxation: relaxes u_ on the patch where R (in r_) sits
  /// (LocalRelaxation); where it did, r_ and `rn` are the relaxed state's. One rank,
  /// conservative problems, not with multigrid.
  bool relax_patch(PetscReal& rn);
  /// A corrector step: c . a and c . b of the bordered system, its load increments (Newton's and
  /// Chebyshev's) and the line search's length of it.
  struct BorderedStep {
    double ca = 0, cb = 0, dalpha = 0, dalpha2 = 0, lambda = 0;
  };
  /// From u_ (r_ = R(u_, s_), a_ = K^-1 f, b_ = K^-1 R): the bordered Newton step for c . u = d
  /// (`m` = c . u_) and its line search (the trial in w_, its residual in b_); taken again with
  /// U^T |D| U where absolute_pivots() says so. False with `why` on a singular system or failed solve.
  bool bordered_step(double d, double m, double rtol, int k, BorderedStep& st, std::string& why);
  /// solver.absolute_pivots or -path_absolute_pivots (opt-in; the option wins), an intermediate
  /// increment (`rtol` above the final one), an indefinite tangent and a factor that can solve with |D|.
  bool absolute_pivots(double rtol) const;
  /// With abandon_off_path: whether a corrector iterate of an intermediate increment (`rtol` above
  /// the final one), on the increment's first try, has left the path: its tangent has more
  /// negative pivots than at the increment's start and the line search cut its step (`lambda`)
  /// below 0.3.
  bool off_the_path(double rtol, double lambda) const;
  /// At the path's final state (converged to rtol): its tangent's inertia where the corrector's
  /// last factor does not give it (a kept factor, multigrid, LU). False with `why` on failure.
  bool inertia_at_final_state(std::string& why);
  /// Node of the largest |u| and the vector c with c . v = (u_k / |u_k|) . v_k; when u = 0,
  /// picked from `fallback`. Returns |u_k|. Collective.
  double control_direction(Vec u, Vec fallback, Vec c);
  /// The global index of every local-vector entry (-1: constrained or not owned here), made at
  /// the first call: control_direction writes its one node straight into the global vector
  /// (DMLocalToGlobal over a constrained section walks every point: 3.5% of a Random2D run).
  const std::vector<PetscInt>& global_of_local();
  /// Assembles K(u_) and solves K a_ = f_ext (Tangent::solve: a kept factor, or a fresh one).
  /// `guess`: a_ holds the response at a nearby state. False if the tangent cannot be formed.
  bool tangent_response(bool guess);
  /// tangent_response(true) and K b = r with the same factor: the corrector's two solves.
  bool tangent_responses(Vec r, Vec b);
  /// negative_pivots_ from the factor just used, where it is of the assembled tangent.
  void inertia_of_response();
  /// tangent_response() at rest (u = 0): K(0) is the same for every load case of the problem
  /// (dead loads), so in 2D its factor is made once and kept (Tangent::use_rest_factor).
  bool rest_response();
  /// Assembles and factorises K(u_) at a converged state: its inertia, exact, is the stability
  /// check (negative_pivots_). False if the tangent cannot be formed or factorised.
  bool factorise_here();
  /// Multigrid: assembles K(u_) at a converged state and checks that it is positive definite
  /// (Tangent::stability) into negative_pivots_. False if it cannot be formed or factorised.
  bool check_stability_here();
  /// A pseudo-random vector keyed by canonical node numbers (the same on any rank count) in v.
  void pseudo_random_vector(Vec v);
  /// All linear-algebra work so far (the path's tangent and the SNES's).
  LinearCounters linear_counters() const;
  /// After a failed path: leaves the state the path ended in (unstable on target: along the
  /// tangent's lowest mode; where increments kept failing: along its mode nearest zero),
  /// minimises the energy there at 0.7^attempt times its load (a stable state on another
  /// branch: past a subcritical bifurcation none is near at the full load), and follows that
  /// branch to the target. Adds its cost to `t`.
  /// Measured on the 8 load cases lost on unseen seeds (777, 2024, 31337; issue 23): 6 end at a
  /// limit point of the load, not a bifurcation. There the switch's minimisation reaches either
  /// the stable state below the fold or the snapped-through one beyond it, and the path from
  /// either comes back to the very unstable state it left (the same alpha to 6 digits, e.g.
  /// seed 777, shape 10, load 28: alpha 61.8964 twice): on an S-shaped alpha(max|u|) curve no
  /// stable state has max|u| = target. Only another branch helps (seed 777, shape 5, load 26: the
  /// third attempt found one with a higher limit load, alpha 66.40 at max|u| 0.442 against 65.53,
  /// and ran out of the Newton budget on its last increment).
  void switch_branch(double target, double start, int attempt, TargetResult& t);
  /// One try of solve_for_target: the path (or the alpha search), its branch switches, the
  /// arc-length rescue and the load-control fallback, from the current state.
  TargetResult attempt_target(double target, double start);
  /// The eigenvector of K(u_) whose eigenvalue is nearest zero (inverse iteration from a
  /// rank-independent pseudo-random vector), in v_, |v_|_inf = 1; returns its Rayleigh quotient.
  double softest_mode();
  /// A thousandth of the mean diagonal of the assembled K(u_): the first trial shift.
  double shift_scale();
  /// With K(u_) assembled and factorised with negative pivots: shifts it to K + mu I, the first
  /// of -2 lam (where the mode nearest zero is negative) or mu0, 4 mu0, ... whose LDL^T has
  /// no negative pivot. Where the mode nearest zero was positive, inverse iteration with that
  /// definite factor then finds K's lowest mode; where it was negative, that mode (a direction of
  /// negative curvature, not necessarily the lowest) is kept. In v_ (|v_|_inf = 1), its Rayleigh
  /// quotient in lam. False if no shift factorised.
  bool shift_past_lowest_mode(double mu0, double& mu, double& lam);
  /// Minimises the energy at load factor s from u_ by a trust-region Newton method: steps of at
  /// most `radius` (|.|_inf; from `eps`, doubled after full steps that filled it, cut to what
  /// the guarded line search took), through curvature_step where K(u_) is indefinite. Ends at
  /// an equilibrium whose tangent is positive definite, or returns false with `why`.
  bool minimise(double s, double eps, int& its, std::string& why);
  /// With K(u_) assembled and factorised (`negative` negative pivots) and R in r_: the step
  /// u_ - du_. Indefinite K: shifted past its lowest eigenvalue (shift_past_lowest_mode), plus a
  /// move along that mode (energy-descending sign) that fills the trust region. False if no
  /// shift factorised.
  bool curvature_step(double radius, double mu0, int negative);

  const physics::Problem& problem_;
  SolverOptions opt_;
  core::SNESH snes_;
  core::MatH J_;
  std::unique_ptr<Tangent> tangent_;  ///< the path's tangent, its factors and Krylov solver
  core::VecH u_, backup_, r_;
  core::VecH a_, a0_, b_, c_, du_, w_, v_, v0_;  ///< displacement-control work vectors
  core::VecH arc_dir_, arc_prev_dir_;  ///< arc_path: the unit direction of the increment, its copy
  bool arc_ = false;         ///< predict/correct constrain c . u (arc_dir_), not max|u|
  double arc_offset_ = 0;    ///< arc_dir_ . u at the increment's start
  std::vector<PetscInt> global_of_local_;  ///< see global_of_local()
  std::unique_ptr<LocalRelaxation> relaxation_;  ///< relax_patch's (made at its first use)
  double s_ = 0;        ///< load factor of the current state
  double s_eval_ = 0;   ///< load factor the callbacks assemble at
  /// The stored energy and internal force of the last trial backtrack evaluated (NaN: none),
  /// and of the state accept_trial copied it to (known_state_, a copy: compared bit for bit;
  /// NaN: none).
  double trial_internal_ = NAN, known_internal_ = NAN;
  core::VecH trial_force_, known_force_, known_state_;
  double ahead_internal_ = NAN;  ///< evaluate_ahead's state (NaN: none): energy, force, the state
  core::VecH ahead_force_, ahead_state_;
  core::VecH curvature_;  ///< second_order_term's K^-1 q (created at its first use)
  double step_hint_ = 0;
  double s0_ = 0;       ///< load factor of the state a branch switch left (in v0_)
  int negative_pivots_ = -1;  ///< inertia of the last tangent_response() (-1: unknown)
  int pivots_at_start_ = -1;  ///< negative_pivots_ where the current increment started
  bool left_path_ = false;    ///< the last corrector stopped because off_the_path held
  bool may_leave_ = true;     ///< off_the_path may end the increment (its last try did not fail)
  LinearCounters snes_linear_;  ///< factorisations of the SNES's own KSP (load control)
  bool user_atol_ = false;
};

}  // namespace hypershape::solver
