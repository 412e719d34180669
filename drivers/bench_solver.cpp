/// bench_solver: where the time of one Neo-Hookean load case goes.
///
/// Scene (the disk/ball problem of the dataset): unit disk (2D) or unit ball (3D),
///   neo_hookean E = 500, nu = 0.49;
///   dirichlet_patch center p_D = (1, 0[, 0]), radius 0.5 (the mesh has vertices on its ends);
///   gaussian_traction center p_N = (-1, 0[, 0]), direction (0, 1[, 0]), gamma 0.2, scaled by
///   alpha, which the alpha search tunes so that max|u| = 0.3.
/// Meshes: mesh::mesh_disk / mesh_ball with ClampRegion{p_D, 0.5}, MeshOptions{h, h / 4}.
///
/// For each (dim, degree, h) and each repeat, in this order (each step timed):
///   mesh; set-up (Problem + NonlinearSolver); first numeric+symbolic factorisation of the
///   tangent at u = 0 on the SNES's own KSP (so the solves below reuse that analysis), then a
///   repeat at u = 0; alpha search from u = 0 (solve_for_target(0.3)); at the converged state
///   u*: energy, residual, Jacobian, the same two through PETSc's pointwise (PetscDS) path,
///   one numeric factorisation and one triangular solve; a full solve at that alpha from u = 0;
///   a second load case from u* (solve_for_target(0.15)).
/// Reported: the median over repeats (all samples go to the JSON). The work is
/// study::run_solver_bench (src/study/bench_solver.cpp).
///
/// Sample runs (OPENBLAS_NUM_THREADS=1; the first, a few seconds, is tests/cli/test_bench_solver.sh):
///   bench_solver --dims 2 --degrees 1 --sizes2d 0.1 --repeats 1 --json bench_tiny.json
///   bench_solver --quick --json bench_quick.json
///   bench_solver --dims 2 --json bench_2d.json
///   bench_solver --dims 3 --degrees 1 --sizes3d 0.3 --repeats 1 -- -log_view
/// Arguments after "--" go to PETSc (solver options, -log_view).
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <iostream>

#include "hypershape/core/petsc_handle.hpp"
#include "hypershape/mesh/gmsh_mesher.hpp"
#include "hypershape/study/bench_solver.hpp"
#include "hypershape/study/output.hpp"

namespace hs = hypershape;

constexpr const char* help_text =
    "bench_solver: per-phase timings of the disk/ball Neo-Hookean solves (see the source "
    "header).\nOptions after \"--\" go to PETSc.\n";

int main(int argc, char** argv) {
  auto [ours, petsc] = hs::study::split_at_dashes(argc, argv);
  hs::study::SolverBenchOptions set;
  CLI::App app{"Per-phase timings of the disk/ball Neo-Hookean solves. Arguments after \"--\" go "
               "to PETSc (e.g. -- -log_view -pc_type lu)."};
  app.add_option("--dims", set.dims, "dimensions to run")->check(CLI::IsMember({2, 3}));
  app.add_option("--degrees", set.degrees, "polynomial degrees")->check(CLI::IsMember({1, 2}));
  app.add_option("--sizes2d", set.sizes2d, "mesh sizes h for the disk")->check(CLI::PositiveNumber);
  app.add_option("--sizes3d", set.sizes3d, "mesh sizes h for the ball")->check(CLI::PositiveNumber);
  app.add_option("--repeats", set.repeats, "repeats per case (median reported)")->check(CLI::Range(1, 100));
  app.add_flag("--quick", set.quick, "only the two coarsest sizes of each dimension");
  app.add_option("--target", set.target, "target max|u| of the alpha search")->check(CLI::PositiveNumber);
  app.add_option("--second-target", set.second_target, "target max|u| of the second load case")
      ->check(CLI::PositiveNumber);
  app.add_option("--json", set.json_path, "write the results here (default: stdout after the tables)");
  try {
    app.parse(ours.count(), ours.data());
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  if (!hs::study::output_writable(set.json_path, "--json")) return 2;
  set.petsc_args.assign(petsc.begin() + 1, petsc.end());

  int petsc_argc = petsc.count();
  char** petsc_argv = petsc.data();
  int my_rank = 0;
  try {
    hs::core::PetscSession petsc_session(&petsc_argc, &petsc_argv, help_text);
    my_rank = hs::core::rank(PETSC_COMM_WORLD);
    hs::mesh::GmshSession gmsh_session;
    hs::study::run_solver_bench(set, std::cout);  // its PETSc objects die before the sessions
  } catch (const std::exception& e) {
    std::cerr << fmt::format("[rank {}] {}\n", my_rank, e.what());
    return 1;
  }
  return 0;
}
