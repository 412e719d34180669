#pragma once
/// Validation of the labels' error estimate (solver::TwoLevelEstimator, issue 19): every case
/// solved as the factory solves it (solve_for_target), its estimate formed as the factory forms
/// it, and its true error measured against a reference at the same traction: the same scene on
/// the mesh refined uniformly once (h/2) and twice (h/4; 2D), nested, so u_h is compared in the
/// reference space exactly (no interpolation, no geometry error), Richardson-extrapolated with
/// the observed order. One JSON object per load case (JSON lines) on `out`.
#include <iosfwd>
#include <string>
#include <vector>

namespace hypershape::study {

struct EstimateStudyOptions {
  std::string preset = "random2d";     ///< dataset preset (or a dataset config file)
  std::string scene;                   ///< "": random shapes of the preset; else an accuracy-study scene
  std::vector<std::int64_t> shapes{0};  ///< shape ids (random mode)
  int loads = 3;                       ///< load cases per shape (scene mode: targets 0.1 0.3 0.5)
  int degree = 0;                      ///< 0: the preset's
  double h = 0;                        ///< 0: the preset's (2D shapes.h, 3D mesh.h)
  int levels = 0;                      ///< reference refinements (0: 2 in 2D, 1 in 3D)
  double graded = -1;                  ///< >= 0, 2D random shapes: mesh.rim = graded x h (0: not graded); < 0: the preset's own
  bool fine_newton = false;            ///< the estimate's fine Newton to tolerance (as for the mean-dilatation element)
  bool references = true;              ///< false: solve and estimate only (no truth; cost and estimate comparisons)
};

/// Runs the cases, one JSON line each on `out` (flushed), progress on stderr. One rank, inside
/// a PETSc and a gmsh session.
void run_estimate_study(const EstimateStudyOptions& options, std::ostream& out);

}  // namespace hypershape::study
