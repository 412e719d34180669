#pragma once
/// The error estimate of a dataset's labels (solver::TwoLevelEstimator) on one shape: the
/// shape's mesh refined once, the dataset's scene built on it (same degree), set to each load
/// case in turn. Built once per shape, on the shape's solver group.
#include <mpi.h>

#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "hypershape/config/dataset.hpp"
#include "hypershape/factory/dataset_scene.hpp"
#include "hypershape/factory/load_cases.hpp"
#include "hypershape/factory/shape_pipeline.hpp"
#include "hypershape/io/dataset_shard.hpp"
#include "hypershape/mesh/refine.hpp"
#include "hypershape/solver/error_estimate.hpp"

namespace hypershape::factory {

class LabelErrorEstimator {
 public:
  /// `coarse`: the shape's problem (built by make_shape_problem from `shape`). The fine Newton
  /// runs to tolerance for the mean-dilatation element, or where `newton_to_tolerance` (the
  /// estimate study's --fine-newton). Collective over `group`.
  LabelErrorEstimator(MPI_Comm group, const config::DatasetConfig& cfg, const ShapeSample& shape,
                      const LoadCase& first, const physics::Problem& coarse, bool newton_to_tolerance = false);
  /// Sets the fine problem to load case `lc` and estimates the error of `u` at `alpha`
  /// (`coarse_solve`: the nonlinear solver's factor, TwoLevelEstimator::estimate). Collective.
  solver::ErrorEstimate estimate(const config::DatasetConfig& cfg, const LoadCase& lc, Vec u, double alpha,
                                 const solver::CoarseSolve& coarse_solve = {});
  const physics::Problem& fine() const { return *fine_.problem; }
  const mesh::RefinedMesh& refined() const { return refined_; }
  const solver::TwoLevelEstimator& estimator() const { return *estimator_; }

 private:
  mesh::RefinedMesh refined_;
  ShapeSample fine_shape_;
  ShapeProblem fine_;
  std::unique_ptr<solver::TwoLevelEstimator> estimator_;
};

/// The labels' estimated errors (loads/error_estimate_rel_l2) over converged load cases: a
/// shape's, a task's run report's; += to sum, sum_over to reduce over the group roots.
struct LabelErrorSummary {
  std::int64_t n = 0, missing = 0, above_1_percent = 0, above_5_percent = 0;  ///< missing: -1 or -2 stored
  std::int64_t inverted = 0;  ///< of the missing: -2, the label inverts inside a cell
  double sum = 0, max = 0;
  LabelErrorSummary& operator+=(const LabelErrorSummary& o);
  /// Summed (max: maximum) over `comm`, counting only the ranks where `contribute`. Collective.
  void sum_over(MPI_Comm comm, bool contribute);
  nlohmann::json json() const;
  std::string line() const;  ///< one line of the printed report ("" when no estimate)
};

/// The per-load-case estimates of one shape, as the shape job stores them
/// (loads/error_estimate_rel_l2, _max_u, _alpha; 0 for a load case that failed, -1 in all
/// three for a converged one whose estimate could not be formed: the fine Newton step found
/// no descent, e.g. a state the refined mesh does not hold stable; -2 (inverted_label) where the
/// label's own field has det F <= 0 inside a cell, at the refined mesh's quadrature points).
/// The estimator is built at
/// the first converged load case.
/// On when the dataset asks for it (representations.error_estimate).
class LabelErrors {
 public:
  static constexpr double inverted_label = -2;  ///< stored where the label inverts inside a cell
  LabelErrors(const config::DatasetConfig& cfg, int n_loads);
  /// Estimates load case `lc` (converged: u at alpha, `coarse_solve` the solver's factor).
  /// Collective over `group`; a failure leaves -1 (a PETSc error is logged), never thrown.
  void estimate(MPI_Comm group, const config::DatasetConfig& cfg, const ShapeSample& shape, const LoadCase& first,
                const LoadCase& lc, const physics::Problem& coarse, Vec u, double alpha,
                const solver::CoarseSolve& coarse_solve);
  /// Load case L's three estimates as `o` holds them.
  void take(std::size_t L, const LabelErrors& o);
  /// Frees the estimator (its refined problem); the estimates stay.
  void release_estimator() { estimator_.reset(); }
  /// From now on, keeps each estimate's fine state (ErrorEstimate::fine_state) and the refined
  /// mesh's node coordinates (group root): a start for the labels on that mesh.
  void keep_fine_states() { keep_fine_states_ = true; }
  /// Load case L's fine state (group root; empty where none was kept) and the nodes it lives on.
  const std::vector<double>& fine_state(std::size_t L) const { return fine_states_[L]; }
  const std::vector<double>& fine_coords() const { return fine_coords_; }
  /// Appends the three arrays (group root).
  void store(std::vector<io::Array>& arrays) const;
  bool enabled() const { return enabled_; }
  /// Per load case: the estimated relative L2 error (0: not converged or not estimated, -1: none formed).
  const std::vector<double>& rel_l2() const { return rel_l2_; }
  /// Over the converged load cases (status 1).
  LabelErrorSummary summary(const std::vector<std::int8_t>& status) const;

 private:
  bool enabled_ = true;
  std::unique_ptr<LabelErrorEstimator> estimator_;
  std::vector<double> rel_l2_, max_u_, alpha_;
  bool keep_fine_states_ = false;
  std::vector<std::vector<double>> fine_states_;  ///< group root: per load case, where kept
  std::vector<double> fine_coords_;               ///< group root: the refined mesh's canonical node coordinates
};

}  // namespace hypershape::factory
