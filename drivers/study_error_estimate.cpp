/// study_error_estimate: validation of the labels' a posteriori error estimate (issue 19;
/// write-up in docs/ACCURACY.md, "Every label knows its own error").
///
/// Each load case is solved as the factory solves it, its estimate formed as the factory forms
/// it (solver::TwoLevelEstimator), and its true error measured at the same traction against
/// the scene on the uniformly refined meshes h/2 and h/4 (3D: h/2), Richardson-extrapolated
/// with the observed order (study::run_estimate_study). One JSON line per load case.
/// Sample runs (one rank; scripts/error_estimate_study.sh runs the table of docs/ACCURACY.md):
///   study_error_estimate --preset random2d_p1 --shapes 0 1 --loads 2 -- -ref_pc_factor_mat_solver_type mumps
///   study_error_estimate --scene disk --degree 2 --h 0.08
#include <CLI/CLI.hpp>
#include <fstream>
#include <iostream>

#include "hypershape/core/petsc_handle.hpp"
#include "hypershape/mesh/gmsh_mesher.hpp"
#include "hypershape/study/error_estimate_study.hpp"
#include "hypershape/study/output.hpp"

namespace hs = hypershape;

int main(int argc, char** argv) {
  auto [ours, petsc] = hs::study::split_at_dashes(argc, argv);
  hs::study::EstimateStudyOptions o;
  std::string out_file;
  CLI::App app{"Validation of the labels' error estimate (docs/ACCURACY.md). Arguments after \"--\" go to PETSc."};
  app.add_option("--preset", o.preset, "dataset preset of the random shapes (default random2d)");
  app.add_option("--scene", o.scene, "an accuracy-study scene instead: disk r2d-0 r2d-1 ood-0 easy-0 ball r3d-0");
  app.add_option("--shapes", o.shapes, "shape ids (random shapes; default 0)");
  app.add_option("--loads", o.loads, "load cases per shape (default 3)")->check(CLI::Range(1, 1000));
  app.add_option("--degree", o.degree, "element degree (default: the preset's)")->check(CLI::IsMember({1, 2}));
  app.add_option("--h", o.h, "element size (default: the preset's)")->check(CLI::PositiveNumber);
  app.add_option("--levels", o.levels, "reference refinements (default 2 in 2D, 1 in 3D)")->check(CLI::Range(1, 3));
  app.add_option("--graded", o.graded,
                 "2D random shapes: the mesh graded towards the clamp ends, this x h there (mesh.rim; e.g. 0.03125, "
                 "the random2d preset's; 0: not graded; default: the preset's own)")
      ->check(CLI::Range(0.0, 1.0));
  app.add_flag("--fine-newton", o.fine_newton, "the estimate's fine Newton to 1% of its first residual, not one step");
  bool estimate_only = false;
  app.add_flag("--estimate-only", estimate_only, "no references: solve and estimate only (the estimate's cost and values)");
  app.add_option("--out", out_file, "JSON lines output (default stdout); appended to");
  try {
    app.parse(ours.count(), ours.data());
    o.references = !estimate_only;
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  int pargc = petsc.count();
  char** pargv = petsc.data();
  try {
    hs::core::PetscSession petsc_session(&pargc, &pargv, nullptr);
    hs::mesh::GmshSession gmsh_session;
    std::ofstream file;
    if (!out_file.empty()) file.open(out_file, std::ios::app);
    hs::study::run_estimate_study(o, out_file.empty() ? std::cout : file);
  } catch (const std::exception& e) {
    std::cerr << "[rank 0] " << e.what() << "\n";
    return 1;
  }
  return 0;
}
