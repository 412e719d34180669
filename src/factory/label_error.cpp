#include "hypershape/factory/label_error.hpp"

#include <fmt/format.h>
#include <petscsys.h>

#include <algorithm>

#include "hypershape/core/log.hpp"
#include "hypershape/factory/dataset_schema.hpp"

namespace hypershape::factory {

LabelErrorEstimator::LabelErrorEstimator(MPI_Comm group, const config::DatasetConfig& cfg, const ShapeSample& shape,
                                         const LoadCase& first, const physics::Problem& coarse,
                                         bool newton_to_tolerance)
    : refined_(mesh::refine_uniform(shape.mesh)) {
  // The fine shape differs only in its mesh: the scene's placements (p_D, r, the loads) come
  // from the shape and the load case, so the fine problem is the same boundary-value problem.
  fine_shape_.shape_id = shape.shape_id;
  fine_shape_.dirichlet_center = shape.dirichlet_center;
  fine_shape_.dirichlet_radius = shape.dirichlet_radius;
  fine_shape_.mesh = refined_.mesh;
  fine_ = make_shape_problem(group, cfg, fine_shape_, first, physics::SpaceOptions{coarse.space().degree(), cfg.quadrature});
  // The mean-dilatation element: Newton to tolerance on the fine mesh (TwoLevelEstimator).
  estimator_ = std::make_unique<solver::TwoLevelEstimator>(coarse, *fine_.problem, refined_,
                                                           newton_to_tolerance || cfg.material.dilatation == "mean");
}

solver::ErrorEstimate LabelErrorEstimator::estimate(const config::DatasetConfig& cfg, const LoadCase& lc, Vec u,
                                                    double alpha, const solver::CoarseSolve& coarse_solve) {
  fine_.set_load_case(cfg, fine_shape_, lc);
  return estimator_->estimate(u, alpha, coarse_solve);
}


LabelErrors::LabelErrors(const config::DatasetConfig& cfg, int n_loads)
    : enabled_(cfg.representations.error_estimate), rel_l2_(std::size_t(n_loads), 0.0),
      max_u_(std::size_t(n_loads), 0.0), alpha_(std::size_t(n_loads), 0.0), fine_states_(std::size_t(n_loads)) {}

LabelErrorSummary LabelErrors::summary(const std::vector<std::int8_t>& status) const {
  LabelErrorSummary s;
  if (!enabled_) return s;
  for (std::size_t k = 0; k < rel_l2_.size() && k < status.size(); ++k) {
    if (!status[k]) continue;
    const double v = rel_l2_[k];
    if (v < 0) {  // -1: no estimate could be formed; -2: nor can be, the label inverts in a cell
      s.missing += 1;
      s.inverted += v == inverted_label;
      continue;
    }
    s.n += 1, s.sum += v, s.max = std::max(s.max, v);
    s.above_1_percent += v > 0.01, s.above_5_percent += v > 0.05;
  }
  return s;
}

LabelErrorSummary& LabelErrorSummary::operator+=(const LabelErrorSummary& o) {
  n += o.n, missing += o.missing, inverted += o.inverted, above_1_percent += o.above_1_percent, above_5_percent += o.above_5_percent;
  sum += o.sum, max = std::max(max, o.max);
  return *this;
}

void LabelErrorSummary::sum_over(MPI_Comm comm, bool contribute) {
  std::int64_t c[5] = {n, missing, inverted, above_1_percent, above_5_percent}, ct[5];
  for (auto& x : c) x = contribute ? x : 0;
  MPI_Allreduce(c, ct, 5, MPI_INT64_T, MPI_SUM, comm);
  n = ct[0], missing = ct[1], inverted = ct[2], above_1_percent = ct[3], above_5_percent = ct[4];
  double x[2] = {contribute ? sum : 0.0, contribute ? max : 0.0}, t[2];
  MPI_Allreduce(&x[0], &t[0], 1, MPI_DOUBLE, MPI_SUM, comm);
  MPI_Allreduce(&x[1], &t[1], 1, MPI_DOUBLE, MPI_MAX, comm);
  sum = t[0], max = t[1];
}

nlohmann::json LabelErrorSummary::json() const {
  return {{"load_cases", n},           {"mean_rel_l2", n ? sum / double(n) : 0.0},
          {"max_rel_l2", max},         {"above_1_percent", above_1_percent},
          {"above_5_percent", above_5_percent}, {"without_estimate", missing},
          {"inverted_in_a_cell", inverted}};
}

std::string LabelErrorSummary::line() const {
  if (n == 0 && missing == 0) return "";
  return fmt::format("  label error estimate (relative L2 of u): mean {:.3g}, max {:.3g}; above 1%: {} of {}, "
                     "above 5%: {}; {} converged load cases without an estimate{}\n",
                     n ? sum / double(n) : 0.0, max, above_1_percent, n, above_5_percent, missing,
                     inverted ? fmt::format(" ({} of them: the label inverts inside a cell)", inverted) : "");
}

void LabelErrors::estimate(MPI_Comm group, const config::DatasetConfig& cfg, const ShapeSample& shape,
                           const LoadCase& first, const LoadCase& lc, const physics::Problem& coarse, Vec u,
                           double alpha, const solver::CoarseSolve& coarse_solve) {
  if (!enabled_) return;
  const auto L = std::size_t(lc.load_id);
  try {
    if (!estimator_) estimator_ = std::make_unique<LabelErrorEstimator>(group, cfg, shape, first, coarse);
    rel_l2_[L] = max_u_[L] = alpha_[L] = -1;  // no estimate (until it is formed)
    solver::ErrorEstimate e = estimator_->estimate(cfg, lc, u, alpha, coarse_solve);
    if (e.inverted) rel_l2_[L] = max_u_[L] = alpha_[L] = inverted_label;
    if (!e.ok) return;
    rel_l2_[L] = e.rel_l2;
    max_u_[L] = e.max_u;
    alpha_[L] = e.alpha;
    if (keep_fine_states_ && !e.fine_state.empty()) {
      if (fine_coords_.empty()) fine_coords_ = estimator_->fine().space().canonical_coords();
      fine_states_[L] = std::move(e.fine_state);
    }
  } catch (const std::runtime_error& e) {  // PETSc's failures: the estimate stays 0
    core::info(group, "shape {} load {}: error estimate failed: {}", shape.shape_id, lc.load_id, e.what());
  }
}

void LabelErrors::take(std::size_t L, const LabelErrors& o) {
  rel_l2_[L] = o.rel_l2_[L], max_u_[L] = o.max_u_[L], alpha_[L] = o.alpha_[L];
}

void LabelErrors::store(std::vector<io::Array>& arrays) const {
  if (!enabled_) return;
  const auto n = std::uint64_t(rel_l2_.size());
  arrays.push_back(schema_array("loads/error_estimate_rel_l2", {n}, rel_l2_));
  arrays.push_back(schema_array("loads/error_estimate_max_u", {n}, max_u_));
  arrays.push_back(schema_array("loads/error_estimate_alpha", {n}, alpha_));
}

}  // namespace hypershape::factory
