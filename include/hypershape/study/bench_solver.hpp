#pragma once
/// The solver benchmark (drivers/bench_solver.cpp): where the time of one Neo-Hookean load case
/// of the disk/ball problem goes.
#include <iosfwd>
#include <string>
#include <vector>

namespace hypershape::study {

struct SolverBenchOptions {
  std::vector<int> dims{2, 3};
  std::vector<int> degrees{1, 2};
  std::vector<double> sizes2d{0.1, 0.05, 0.025};
  std::vector<double> sizes3d{0.3, 0.2, 0.15};
  int repeats = 3;
  bool quick = false;          ///< only the two coarsest sizes of each dimension
  double target = 0.3;         ///< max|u| of the alpha search
  double second_target = 0.15; ///< max|u| of the second load case
  std::string json_path;       ///< empty: the JSON goes to `table` after the tables
  std::vector<std::string> petsc_args;  ///< recorded in the JSON (already in the options database)
};

/// Every (dim, degree, h) case, `repeats` times: mesh, set-up, factorisations, alpha search,
/// kernels at the converged state, a full solve and a second load case, each timed (PETSc log
/// stages "bench: ..."). Medians print as tables on `table` (rank 0); the JSON (every sample)
/// is written after every case. Collective over PETSC_COMM_WORLD, inside a PETSc and a gmsh
/// session.
void run_solver_bench(const SolverBenchOptions& options, std::ostream& table);

}  // namespace hypershape::study
