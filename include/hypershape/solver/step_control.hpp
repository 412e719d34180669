#pragma once
/// The displacement-controlled path's step control (path_following.cpp): how long the next
/// increment is, and when an increment's Newton iterations are given up.
#include <algorithm>
#include <array>
#include <cstddef>

namespace hypershape::solver {

/// The next increment after one whose corrector took `n` iterations: `growth` times it after
/// <= 2 (step_growth), halved after >= 6. Measured on Random2D (8 x 25, P1): the increment
/// after a doubling failed in 13%, 11% and 18% of cases after 1, 2 and 3 iterations (a failure
/// costs 5.7 iterations, an accepted intermediate increment 3.1); doubling after <= 3 and
/// halving after >= 8 (before): 13.3 Newton iterations per load case, doubling after <= 2 and
/// halving after >= 6: 12.6 (0.24 failed increments per load case against 0.34), all 200
/// converged. Growing by 1.5 instead of 2 (issue 23, 1000 load cases on
/// each of five unseen seeds, P1 and P2): 1-7.5% fewer Newton iterations, 13-39% fewer in
/// discarded increments, the same converged share (docs/SOLVER.md).
inline double next_step(double step, int n, double growth) {
  if (n <= 2) return growth * step;
  return n >= 6 ? 0.5 * step : step;
}

/// The growth of an increment after an easy one: SolverOptions::step_growth, or where that is 0
/// (the default), by dimension: 1.5 in 2D, 2 in 3D. In 3D 1.5 did not pay (the Random3D preset,
/// 200 load cases of seed 90210: 13.0 -> 13.1 Newton iterations per load case, 200 -> 199
/// converged), so 3D paths keep the former 2.
inline double step_growth(double configured, int dim) {
  if (configured > 0) return configured;
  return dim == 2 ? 1.5 : 2.0;
}

/// The next load case's first increment (the hint, first_step) after this one's first accepted
/// increment of length `first`: `whole` (it reached the target), `first_try` (no increment failed
/// before it), `n` its corrector's iterations; `hint` the one it started with (0: none).
/// Halved until it converged: that length. The whole target at once and easily (to the final
/// tolerance, so one iteration more than an intermediate state's <= 2): no sign that the longer
/// hint is too long, so it stays. Otherwise the first increment, halved after a hard one as
/// next_step halves within a path. Before (the first increment, whatever it was), one small target
/// shortened the first increment of every load case after it: the disk's targets 0.3, 0.1, 0.5,
/// 0.2, 0.4 in turn, twice (`hypershape solve --targets --repeat 2`), Newton iterations P1 h 0.04
/// 45 -> 40, P2 h 0.08 74 -> 70, h 0.05 90 -> 90; on Random2D (seed 2024, 20 x 25) P1 4964 ->
/// 4891, P2 8047 -> 8045, three unseen seeds x 1000 load cases at P2 the same 1000 / 996 / 995
/// converged, 17.1 / 19.6 / 19.3 -> 16.9 / 19.9 / 19.0 per load case; Random3D (seed 90210,
/// 10 x 20) 1975 -> 1995, the same 200 converged.
inline double next_hint(double hint, double first, bool whole, bool first_try, int n) {
  if (!first_try) return first;
  if (whole && n <= 3) return std::max(hint, first);
  return n >= 6 ? 0.5 * first : first;
}

/// Newton creeping in an increment: the line search cut each of the last three steps below 0.3
/// of Newton's step and the residual did not halve over them. Such increments mostly failed
/// later anyway (no convergence in max_newton, or no progress), after 4-9 more iterations at
/// steps of 1e-3 or less; failing at once halves the increment sooner. Measured side by side
/// (docs/SOLVER.md).
class CreepWatch {
 public:
  static constexpr int window = 3;           ///< steps looked at
  static constexpr double cut = 0.3;         ///< a step shorter than this fraction of Newton's is cut
  static constexpr double reduction = 0.5;   ///< |R| must fall below this factor over the window
  /// Why the increment failed (the reason a load case records when it was its last failure).
  static constexpr const char* reason =
      "Newton creeping (3 steps cut below 0.3 by the line search, |R| not halved)";

  explicit CreepWatch(double rn) { rn_[0] = rn; }
  /// A step of `lambda` times Newton's taken, leaving the residual norm `rn`.
  void step(double lambda, double rn) {
    lambda_[std::size_t(steps_ % window)] = lambda;
    ++steps_;
    rn_[std::size_t(steps_ % (window + 1))] = rn;
  }
  bool creeping() const {
    if (steps_ < window) return false;
    for (double l : lambda_)
      if (!(l < cut)) return false;
    return rn_[std::size_t(steps_ % (window + 1))] > reduction * rn_[std::size_t((steps_ - window) % (window + 1))];
  }

 private:
  std::array<double, window + 1> rn_{};  ///< the residual norms after the last window + 1 steps
  std::array<double, window> lambda_{};  ///< the last window step lengths
  int steps_ = 0;
};

}  // namespace hypershape::solver
