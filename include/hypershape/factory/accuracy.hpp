#pragma once
/// Datasets asked for by accuracy (issue 19; config `accuracy: {rel_l2: B}`): each load case is
/// solved on a ladder of discretisations, from the config's own (level 0) upwards, until the error
/// estimate of its label (factory/label_error.hpp) meets the bound B.
///
/// The ladder, from the config's `mesh.degree` p and the drawn mesh M (element size h):
///   p = 1: level 0 P1 on M, level 1 P2 on M, level k >= 2 P2 on M refined uniformly k - 1 times;
///   p = 2: level k P2 on M refined k times.
/// Uniform refinement (mesh::refine_uniform) keeps the shape: the same polygon / surface, p_D,
/// patch and load placements (drawn once, from the shape as drawn), so every level solves the
/// same boundary-value problem and only its discretisation moves; and the levels are nested
/// (each one's fields are fields of the next), so a label carries to a finer level exactly.
///
/// Load case by load case (LoadLadder, factory/shape_job.cpp, since 2026-12-02): every load case
/// is solved at level 0; one whose estimate misses B where a higher level is predicted to meet it
/// (curable()) is solved again at the lowest level predicted to (next_accuracy_level()), and so on
/// up to accuracy.max_level. Its label is the one with the smallest estimate it reached: a
/// re-solve that fails, forms no estimate or estimates no lower keeps the label it had (measured,
/// 2026-12-01, EasyRandom2D: the finer levels lose or flag some labels that converge at level 0);
/// it then tries a level it jumped past, or climbs on from its own estimate if it converged
/// (LoadLadder). No load case of a shape climbs while at most floor(exceed_share * loads.count)
/// would. The shape is stored on the finest level one of its labels was kept at, the others
/// carried to that mesh. A load case no level is predicted to bring under B is counted above B and
/// does not climb (climbing for them cost 101x the level-0 run's CPU for a lower share under B:
/// docs/ACCURACY.md, "What each bound costs"). Every choice is a function of the estimates, which
/// are functions of the data: 1 rank and 2 ranks choose the same levels.
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

/// p with node j of `to` at node p[j] of `from` (coordinates n x dim, equal bit for bit: the same
/// mesh numbered twice, e.g. the estimator's refined mesh and the next level's); empty if the two
/// node sets differ.
std::vector<std::int64_t> node_permutation(const std::vector<double>& from, const std::vector<double>& to, int dim);

/// The predicted factor by which the estimate falls from level `from` to level `to`: 10 for P1 -> P2
/// on the same mesh (measured 8-20: docs/ACCURACY.md, P1 h 0.04 against P2 h 0.08 on the accuracy
/// study's scenes, at error order ~1), 2 per uniform refinement (the order 1 the estimate assumes).
double predicted_reduction(const AccuracyLevel& from, const AccuracyLevel& to);

/// The level to try after `current` for a label whose estimate was `worst` (< 0: none formed): the
/// lowest above `current` predicted to meet the bound, at most accuracy.max_level.
int next_accuracy_level(const config::DatasetConfig& cfg, int current, double worst);

/// Whether a converged load case's estimate `rel_l2` (-1: none) misses the bound.
inline bool exceeds(const config::AccuracyConfig& a, double rel_l2) { return rel_l2 < 0 || rel_l2 > a.rel_l2; }

/// Whether a load case that misses the bound at level `current` (exceeds()) is worth a higher
/// level: it has no estimate, or its estimate over predicted_reduction() to the last level meets
/// the bound.
bool curable(const config::DatasetConfig& cfg, int current, double rel_l2);

/// The ladder's schedule for the load cases of one shape (not collective: every rank of a group
/// records the same outcomes, so keeps the same schedule). Every load case is first solved at level
/// 0; then, while more than floor(exceed_share * loads) load cases wait, those waiting for the
/// lowest level are solved there (next()), and each outcome is recorded (record()).
///
/// A load case waits for the lowest level above its kept label's predicted to meet the bound
/// (next_accuracy_level()), when its label misses it and is curable() and that level is untried;
/// with `accuracy: {start: coarse}`, for the next level up (one at a time, so that each re-solve
/// can start from the state the level below's estimate reached: shape_job.cpp).
/// A re-solve whose label is not kept (it failed, formed no estimate or estimated no lower):
///  - after a jump past levels it never tried, falls back to the highest of those (Random2D at
///    0.01, 2026-12-02: jumps from level 0 to 2 that failed there, of labels that met the bound at
///    level 1 in another run);
///  - else, if it converged, climbs on from its own estimate, as a kept label would (a level-1
///    label flagged -2, or estimated above the level-0 one, met the bound at level 2: 93.5% ->
///    95.0% on Random2D at 0.01);
///  - else (it failed) ends the climb.
class LoadLadder {
 public:
  LoadLadder(const config::DatasetConfig& cfg, int n_loads);
  /// Load case L solved at level k: whether it converged and its estimate (< 0: none). Returns
  /// whether its label is the one kept (level 0's always is; a higher level's when it converged
  /// with an estimate lower than the kept label's, or the kept one had none).
  bool record(int L, int k, bool converged, double estimate);
  /// The level to solve next (-1: none; the shape is done) and, in `loads`, the load cases to
  /// solve there.
  int next(std::vector<int>& loads) const;
  int kept(int L) const { return kept_[std::size_t(L)]; }             ///< the kept label's level
  int waiting(int L) const { return waiting_[std::size_t(L)]; }       ///< the level L waits for (-1: none)
  bool falls_back(int L) const { return waiting(L) >= 0 && waiting(L) < highest_tried(L); }  ///< to a level it skipped
  int highest_tried(int L) const;                                     ///< the highest level L was solved at
  const std::vector<int>& kept_levels() const { return kept_; }

 private:
  bool tried(int L, int k) const { return (tried_[std::size_t(L)] >> k) & 1U; }
  int climb(int L, int from, double e) const;  ///< where L waits for from a label of level `from`, estimate e (-1: stays)
  const config::DatasetConfig& cfg_;
  std::size_t allowed_;
  std::vector<int> kept_, waiting_;
  std::vector<unsigned> tried_;  ///< bit k: solved at level k
  std::vector<double> estimate_;  ///< the kept label's (-1: none yet or failed)
};

/// `shape` on its mesh refined uniformly once: the boundary's facets split (2 per segment, 4 per
/// triangle, orientation kept) and renumbered so that boundary point i is still mesh vertex i,
/// the Dirichlet facets their children; p_D, r, metrics and the draw's record unchanged. Not
/// collective.
ShapeSample refine_shape(const ShapeSample& shape);

/// What the accuracy ladder did over a set of shapes (a shape's job, a run report).
struct AccuracySummary {
  static constexpr int kLevels = 4;
  std::array<std::int64_t, kLevels> shapes_at_level{};  ///< shapes stored at each level (their finest label's)
  std::array<std::int64_t, kLevels> loads_at_level{};   ///< converged load cases whose label is of each level
  std::int64_t loads_meeting = 0;    ///< converged load cases, estimate <= bound
  std::int64_t loads_exceeding = 0;  ///< converged, estimate > bound or none
  std::int64_t solved_again = 0;      ///< load cases solved again at a higher level
  std::int64_t fell_back = 0;         ///< re-solves at a level a load case had jumped past (LoadLadder)
  std::int64_t discarded_loads = 0;  ///< labels solved (and estimated) and not kept
  std::int64_t discarded_newton = 0, discarded_factorizations = 0;  ///< what those cost
  AccuracySummary& operator+=(const AccuracySummary& o);
  /// Summed over `comm`, counting only the ranks where `contribute`. Collective.
  void sum_over(MPI_Comm comm, bool contribute);
  std::int64_t shapes() const;
  nlohmann::json json(const config::AccuracyConfig& a) const;
  std::string line(const config::AccuracyConfig& a) const;  ///< printed summary ("" when off)
};

}  // namespace hypershape::factory
