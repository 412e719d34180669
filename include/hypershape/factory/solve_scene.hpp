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
  /// One entry per solve (repeats x targets; one without them): target (0 at a given alpha),
  /// alpha, max|u|, converged, Newton iterations and seconds, from rest (u = 0) to the answer,
  /// the nonlinear solver's work only (no mesh, set-up, max|u| or output).
  struct LoadCase {
    double target = 0, alpha = 0, max_displacement = 0, seconds = 0;
    int newton_iterations = 0;
    bool converged = false;
  };
  std::vector<LoadCase> load_cases;
  io::SolutionRecord record;  ///< significant on rank 0
};

/// Builds every effect of the scene and checks the scene is solvable (a material, a Dirichlet
/// condition) before any collective work; throws core::InputError on every rank otherwise.
/// Collective over `comm`.
/// Benchmark runs of one scene: `targets` (if not empty) replace the scene's load.target and
/// are solved in turn, the whole list `repeat` times, each load case from rest on the same
/// problem and solver (as the factory solves the load cases of a shape); the last is kept.
struct SceneRuns {
  int repeat = 1;
  std::vector<double> targets;
};
SceneOutcome solve_scene(MPI_Comm comm, const config::Scene& scene, const SceneRuns& runs = {});

/// One line: dimension, sizes, alpha, max|u|, iterations, phase times.
std::string summary_line(const SceneOutcome& o);

}  // namespace hypershape::factory
