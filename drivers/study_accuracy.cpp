/// study_accuracy: what accuracy costs in time (issue 6; write-up in docs/ACCURACY.md).
///
/// The problem of every sample of a dataset: find u and alpha with equilibrium of the
/// compressible Neo-Hookean body (E, nu of the dataset) clamped on the Dirichlet patch
/// |x - p_D| <= r and loaded by alpha g phi(x - p_N) / I_N, such that max|u| = target
/// (NonlinearSolver::solve_for_target). For a fixed set of scenes this driver solves that
/// problem with many settings (mesh size h, degree, quadrature, tolerances, continuation,
/// linear solver, the linear small-strain model) and measures each against a reference:
///
/// Scenes (fixed seeds, the presets' seeds and the dataset defaults for E, nu, r, gamma, h,
/// degree and solver options; every h of a scene discretises the same problem, same p_D):
///   disk    the unit disk, p_D = (1, 0), Random2D's parameters (the seed paper's scene)
///   r2d-0   Random2D shape 0, r2d-1 Random2D shape 1, ood-0 OODRandom2D shape 0
///           (factory::make_shape at every h; the first id from these whose draw is accepted at
///           the same attempt at every h)
///   ball    the unit ball, p_D = (1, 0, 0), Random3D's parameters
///   r3d-0   Random3D shape 0 (drawn at the finest h, its surface remeshed at the coarser ones)
/// (see ShapeCache in src/study/accuracy_detail.hpp). Load cases: p_N and g from factory::draw_load_cases on the baseline shape
/// (the preset's h), the targets set to 0.1, 0.3, 0.5 (--tiny: the middle one).
///
/// Reference per scene: P2 on the same shape meshed at h_ref (2D 0.02, 3D 0.2), rtol 1e-10,
/// target_rtol 1e-6, MUMPS LDL^T. Its own discretisation error is estimated by Richardson
/// extrapolation from the ladder h_ref, 2 h_ref, 4 h_ref (3D: two levels; P2, same tolerances): with d1 = ||u_2h - u_h|| and
/// d2 = ||u_4h - u_2h|| (both at the reference's nodes, relative to ||u_h||) the observed order
/// is p = log2(d2 / d1) and the error of u_h about d1 / (2^p - 1) (p clamped to [0.5, 4]; with
/// two levels only, p = 1 is assumed and flagged).
///
/// Metrics per setting and load case: the coarse field is evaluated at the reference's nodes
/// with sampling::MeshSampler (FE interpolant inside the coarse mesh, closest-point extension
/// outside it), then relative L2 and H1 in the seed paper's discrete form
/// (sampling::NodalNorms: nodal values, recovered nodal gradients of the reference mesh), the
/// relative error of alpha, |max|u| / target - 1|, the wall and CPU time of the load case
/// (traction set-up + reset + solve_for_target; median of the repeats), and once per setting the DoFs,
/// the mesh and set-up times and the peak resident memory of the setting (VmHWM after a reset
/// through /proc/self/clear_refs). Settings on the baseline discretisation also get their
/// "solver error": the relative L2 distance at their own nodes to the same discretisation
/// solved with tight tolerances.
///
/// The linear model: u_lin = alpha_lin K(0)^-1 f_ext with alpha_lin = target / max|K(0)^-1
/// f_ext| (one factorisation of the tangent at u = 0 and one solve, on the solver's KSP): the
/// small-strain solution scaled so that its max|u| hits the target exactly.
///
/// The study is study::run_accuracy_study (src/study/accuracy*.cpp); this file parses the
/// command line. One rank only. Sample runs (OPENBLAS_NUM_THREADS=1; times on a shared 2-core
/// VM; the first is tests/cli/test_study_accuracy.sh):
///   study_accuracy --tiny --out results/study_accuracy_tiny.json          (~15-45 s; CI)
///   study_accuracy --full --dims 2 --out results/study_accuracy_2d.json   (~15 min)
///   study_accuracy --full --out results/study_accuracy.json               (scripts/study_accuracy.sh)
/// Arguments after "--" go to PETSc.
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <iostream>

#include "hypershape/core/petsc_handle.hpp"
#include "hypershape/mesh/gmsh_mesher.hpp"
#include "hypershape/study/accuracy.hpp"
#include "hypershape/study/output.hpp"

namespace hs = hypershape;

constexpr const char* help_text =
    "study_accuracy: the accuracy/time study (see the source header and docs/ACCURACY.md).\n"
    "Options after \"--\" go to PETSc.\n";

int main(int argc, char** argv) {
  auto [ours, petsc] = hs::study::split_at_dashes(argc, argv);
  hs::study::AccuracyOptions a;
  CLI::App app{"The accuracy/time study (docs/ACCURACY.md). Arguments after \"--\" go to PETSc."};
  auto* tiny = app.add_flag("--tiny", a.tiny, "CI version: the disk, P1/P2 at coarse h, a coarse reference, 1 load case");
  app.add_flag("--full", a.full, "the whole study (default)")->excludes(tiny);
  app.add_option("--out", a.out, "JSON results (default results/study_accuracy.json)");
  app.add_option("--dump", a.dump, "also write the arrays of one setting and the reference (JSON) for checks");
  app.add_option("--dims", a.dims, "dimensions to run (full mode)")->check(CLI::IsMember({2, 3}));
  app.add_option("--scenes", a.scenes, "scene names to run (disk r2d-0 r2d-1 ood-0 easy-0 ball r3d-0)");
  app.add_option("--repeats", a.repeats, "repeats per load case (default 3; tiny 1)")->check(CLI::Range(1, 50));
  app.add_option("--repeat-above", a.repeat_above, "a load case whose first run takes longer (s) is not repeated")
      ->check(CLI::PositiveNumber);
  app.add_option("--ref-h2d", a.ref_h2d, "reference mesh size in 2D (default 0.02)")->check(CLI::PositiveNumber);
  app.add_option("--ref-h3d", a.ref_h3d, "reference mesh size in 3D (default 0.2)")->check(CLI::PositiveNumber);
  app.add_option("--override", a.override_yaml,
                 "dataset-config YAML merged over every scene's preset, e.g. 'shapes: {max_turn_deg: 30}'");
  app.add_flag("--grid-only", a.grid_only, "the h x degree grid and the linear model only (no tolerance, "
               "control, quadrature or linear-solver knobs)");
  app.add_flag("-v,--verbose", a.verbose, "a progress line per load case (always for the reference)");
  app.add_option("--ladder", a.ladder, "2D reference levels for Richardson: 2 or 3")->check(CLI::Range(2, 3));
  app.add_option("--ladder3d", a.ladder3d, "3D reference levels for Richardson: 2 or 3")->check(CLI::Range(2, 3));
  app.add_option("--ref-grading", a.ref_grading,
                 "disk references: boundary chord at the patch ends as a fraction of h (default 1: "
                 "ungraded; graded references weight the patch ends in the node-averaged metrics)")
      ->check(CLI::Range(0.01, 1.0));
  app.add_option("--sizes2d", a.sizes2d, "2D mesh sizes of the h x degree grid (full)")->check(CLI::PositiveNumber);
  app.add_option("--sizes3d", a.sizes3d, "3D mesh sizes of the h x degree grid (full)")->check(CLI::PositiveNumber);
  try {
    app.parse(ours.count(), ours.data());
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  if (!hs::study::output_writable(a.out, "--out") || !hs::study::output_writable(a.dump, "--dump")) return 2;
  hs::study::apply_defaults(a);
  a.petsc_args.assign(petsc.begin() + 1, petsc.end());

  int petsc_argc = petsc.count();
  char** petsc_argv = petsc.data();
  try {
    hs::core::PetscSession petsc_session(&petsc_argc, &petsc_argv, help_text);
    hs::mesh::GmshSession gmsh_session;
    hs::study::run_accuracy_study(a, std::cout);
  } catch (const std::exception& e) {
    std::cerr << fmt::format("[rank 0] {}\n", e.what());
    return 1;
  }
  return 0;
}
