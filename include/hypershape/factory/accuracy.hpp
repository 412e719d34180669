#pragma once
/// Datasets asked for by accuracy (issue 19; config `accuracy: {rel_l2: B}`): each shape is solved
/// on a ladder of discretisations, from the config's own (level 0) upwards, until the error
/// estimate of its load cases (factory/label_error.hpp) meets the bound B. All load cases of a
/// shape share the level (one mesh, one set of per-shape arrays).
///
/// The ladder, from the config's `mesh.degree` p and the drawn mesh M (element size h):
///   p = 1: level 0 P1 on M, level 1 P2 on M, level k >= 2 P2 on M refined uniformly k - 1 times;
///   p = 2: level k P2 on M refined k times.
/// Uniform refinement (mesh::refine_uniform) keeps the shape: the same polygon / surface, p_D,
/// patch and load placements (drawn once, from the shape as drawn), so every level solves the
/// same boundary-value problem and only its discretisation moves.
///
/// Levels are tried in order of need: a level is abandoned as soon as more than
/// floor(exceed_share * loads.count) of its converged load cases estimate above B where a higher
/// level is predicted to meet it (curable()), or have no estimate; the next level is the lowest
/// whose predicted estimate, the worst curable one seen divided by predicted_reduction(), meets
/// B. A load case that not even the last level is predicted to bring under B is counted above B
/// and does not move its shape: measured (2026-12-01, EasyRandom2D at B = 0.05), the finer
/// levels lost or flagged as many labels as they cured, and climbing for such labels made the
/// run 101x the level-0 run's CPU for a lower share under B than level 0's own (docs/ACCURACY.md,
/// "What each bound costs"). The last level (accuracy.max_level) is kept whatever its
/// estimates, its load cases above B counted as such. Every choice is a function of the
/// estimates, which are functions of the data: 1 rank and 2 ranks choose the same levels.
#include <mpi.h>

#include <array>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "hypershape/config/dataset.hpp"
#include "hypershape/factory/shape_pipeline.hpp"

namespace hypershape::factory {

/// One rung of the ladder.
struct AccuracyLevel {
  int level = 0;
  int degree = 1;       ///< element degree
  int refinements = 0;  ///< uniform refinements of the drawn mesh
  double h = 0;         ///< nominal element size: shapes.h (3D: max(shapes.h, mesh.h)) / 2^refinements
};

/// Level `level` of `cfg`'s ladder (not collective).
AccuracyLevel accuracy_level(const config::DatasetConfig& cfg, int level);

/// The predicted factor by which the estimate falls from level `from` to level `to`: 10 for P1 -> P2
/// on the same mesh (measured 8-20: docs/ACCURACY.md, P1 h 0.04 against P2 h 0.08 on the accuracy
/// study's scenes, at error order ~1), 2 per uniform refinement (the order 1 the estimate assumes).
double predicted_reduction(const AccuracyLevel& from, const AccuracyLevel& to);

/// The level to try after `current` when its worst curable estimate was `worst` (< 0: none
/// formed): the lowest above `current` predicted to meet the bound, at most accuracy.max_level.
int next_accuracy_level(const config::DatasetConfig& cfg, int current, double worst);

/// Whether a converged load case's estimate `rel_l2` (-1: none) misses the bound.
inline bool exceeds(const config::AccuracyConfig& a, double rel_l2) { return rel_l2 < 0 || rel_l2 > a.rel_l2; }

/// Whether a load case that misses the bound at level `current` (exceeds()) is worth a higher
/// level: it has no estimate, or its estimate over predicted_reduction() to the last level meets
/// the bound.
bool curable(const config::DatasetConfig& cfg, int current, double rel_l2);

/// `shape` on its mesh refined uniformly once: the boundary's facets split (2 per segment, 4 per
/// triangle, orientation kept) and renumbered so that boundary point i is still mesh vertex i,
/// the Dirichlet facets their children; p_D, r, metrics and the draw's record unchanged. Not
/// collective.
ShapeSample refine_shape(const ShapeSample& shape);

/// What the accuracy ladder did over a set of shapes (a shape's job, a run report).
struct AccuracySummary {
  static constexpr int kLevels = 4;
  std::array<std::int64_t, kLevels> shapes_at_level{};  ///< shapes kept at each level
  std::int64_t loads_meeting = 0;    ///< converged load cases of kept levels, estimate <= bound
  std::int64_t loads_exceeding = 0;  ///< converged, estimate > bound or none (kept at max_level)
  std::int64_t escalations = 0;      ///< levels abandoned
  std::int64_t discarded_loads = 0;  ///< load cases solved (and estimated) at abandoned levels
  std::int64_t discarded_newton = 0, discarded_factorizations = 0;
  AccuracySummary& operator+=(const AccuracySummary& o);
  /// Summed over `comm`, counting only the ranks where `contribute`. Collective.
  void sum_over(MPI_Comm comm, bool contribute);
  std::int64_t shapes() const;
  nlohmann::json json(const config::AccuracyConfig& a) const;
  std::string line(const config::AccuracyConfig& a) const;  ///< printed summary ("" when off)
};

}  // namespace hypershape::factory
