#include "hypershape/factory/label_error.hpp"

#include <petscsys.h>

#include "hypershape/core/log.hpp"
#include "hypershape/factory/dataset_schema.hpp"

namespace hypershape::factory {

LabelErrorEstimator::LabelErrorEstimator(MPI_Comm group, const config::DatasetConfig& cfg, const ShapeSample& shape,
                                         const LoadCase& first, const physics::Problem& coarse)
    : refined_(mesh::refine_uniform(shape.mesh)) {
  // The fine shape differs only in its mesh: the scene's placements (p_D, r, the loads) come
  // from the shape and the load case, so the fine problem is the same boundary-value problem.
  fine_shape_.shape_id = shape.shape_id;
  fine_shape_.dirichlet_center = shape.dirichlet_center;
  fine_shape_.dirichlet_radius = shape.dirichlet_radius;
  fine_shape_.mesh = refined_.mesh;
  fine_ = make_shape_problem(group, cfg, fine_shape_, first, physics::SpaceOptions{coarse.space().degree()});
  estimator_ = std::make_unique<solver::TwoLevelEstimator>(coarse, *fine_.problem, refined_);
}

solver::ErrorEstimate LabelErrorEstimator::estimate(const config::DatasetConfig& cfg, const LoadCase& lc, Vec u,
                                                    double alpha) {
  fine_.set_load_case(cfg, fine_shape_, lc);
  return estimator_->estimate(u, alpha);
}


LabelErrors::LabelErrors(int n_loads)
    : rel_l2_(std::size_t(n_loads), 0.0), max_u_(std::size_t(n_loads), 0.0), alpha_(std::size_t(n_loads), 0.0) {
  PetscBool on = PETSC_TRUE;
  PetscOptionsGetBool(nullptr, nullptr, "-error_estimate", &on, nullptr);
  enabled_ = on == PETSC_TRUE;
}

void LabelErrors::estimate(MPI_Comm group, const config::DatasetConfig& cfg, const ShapeSample& shape,
                           const LoadCase& first, const LoadCase& lc, const physics::Problem& coarse, Vec u,
                           double alpha) {
  if (!enabled_) return;
  const auto L = std::size_t(lc.load_id);
  try {
    if (!estimator_) estimator_ = std::make_unique<LabelErrorEstimator>(group, cfg, shape, first, coarse);
    rel_l2_[L] = max_u_[L] = alpha_[L] = -1;  // no estimate (until it is formed)
    const solver::ErrorEstimate e = estimator_->estimate(cfg, lc, u, alpha);
    if (!e.ok) return;
    rel_l2_[L] = e.rel_l2;
    max_u_[L] = e.max_u;
    alpha_[L] = e.alpha;
  } catch (const std::runtime_error& e) {  // PETSc's failures: the estimate stays 0
    core::info(group, "shape {} load {}: error estimate failed: {}", shape.shape_id, lc.load_id, e.what());
  }
}

void LabelErrors::store(std::vector<io::Array>& arrays) const {
  if (!enabled_) return;
  const auto n = std::uint64_t(rel_l2_.size());
  arrays.push_back(schema_array("loads/error_estimate_rel_l2", {n}, rel_l2_));
  arrays.push_back(schema_array("loads/error_estimate_max_u", {n}, max_u_));
  arrays.push_back(schema_array("loads/error_estimate_alpha", {n}, alpha_));
}

}  // namespace hypershape::factory
