#pragma once
/// What the solver spent on a set of load cases and how they ended: one type for a shape's job
/// (ShapeJobResult), a task's run report (RunReport, reports/*.json) and the printed summary.
/// Counted where it happens (solver::TargetResult), summed with +=, reduced over ranks once.
#include <mpi.h>

#include <cstdint>
#include <nlohmann/json.hpp>

#include "hypershape/solver/nonlinear.hpp"

namespace hypershape::factory {

struct SolveCounters {
  std::int64_t loads_ok = 0, loads_failed = 0;
  std::int64_t newton_iterations = 0;    ///< all Newton iterations, failed increments' included
  std::int64_t solves = 0;               ///< increments tried (alpha evaluations under load control)
  std::int64_t failed_increments = 0;    ///< increments that failed and were halved
  std::int64_t off_path_increments = 0;  ///< of those: abandoned off the path (an indefinite damped step)
  std::int64_t recovery_iterations = 0;  ///< Newton iterations spent in failed increments
  solver::LinearCounters linear;         ///< factorisations, Krylov iterations, tangent assemblies

  /// One load case's solve (its cost; whether it converged is counted by the caller, who may
  /// still reject the result, e.g. for inverted cells).
  void add(const solver::TargetResult& r);
  SolveCounters& operator+=(const SolveCounters& o);
  /// Every counter summed over `comm`, counting only the ranks where `contribute` (e.g. the
  /// roots of solver groups, which hold their group's numbers once). Collective.
  void sum_over(MPI_Comm comm, bool contribute);
  std::int64_t loads() const { return loads_ok + loads_failed; }
  /// The report's "solver" object: every counter by name.
  nlohmann::json solver_json() const;
};

}  // namespace hypershape::factory
