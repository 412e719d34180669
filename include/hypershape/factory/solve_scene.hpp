#pragma once
/// Solves one scene end to end: mesh -> problem -> nonlinear solve (alpha given, or tuned to a
/// target max|u|) -> a record ready to be written. The driver behind `hypershape solve`.
#include <mpi.h>

#include <string>
#include <vector>

#include "hypershape/config/scene.hpp"
#include "hypershape/core/timer.hpp"
#include "hypershape/io/solution_file.hpp"

namespace hypershape::factory {

struct SceneOutcome {
  bool converged = false;
  std::string reason;
  double alpha = 0, max_displacement = 0, min_det_f = 0;
  int newton_iterations = 0, solves = 0, failed_increments = 0;
  std::int64_t n_vertices = 0, n_cells = 0, n_dofs = 0;
  int dim = 0, degree = 0;
  core::PhaseTimes times;     ///< mesh, setup, solve, gather
  /// Seconds of each solve of the load case (one per repeat): from rest (u = 0) to the
  /// converged answer, the nonlinear solver's work only (no mesh, set-up, max|u| or output).
  std::vector<double> load_case_seconds;
  io::SolutionRecord record;  ///< significant on rank 0
};

/// Builds every effect of the scene and checks the scene is solvable (a material, a Dirichlet
/// condition) before any collective work; throws core::InputError on every rank otherwise.
/// Collective over `comm`.
/// `repeats` > 1 solves the load case that many times, each from rest on the same problem and
/// solver (as the factory solves the load cases of a shape), for timing; the last is kept.
SceneOutcome solve_scene(MPI_Comm comm, const config::Scene& scene, int repeats = 1);

/// One line: dimension, sizes, alpha, max|u|, iterations, phase times.
std::string summary_line(const SceneOutcome& o);

}  // namespace hypershape::factory
