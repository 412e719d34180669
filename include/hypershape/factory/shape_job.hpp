#pragma once
/// One shape of a dataset, end to end, on a group of ranks: draw and mesh the shape, set up the
/// problem once (mesh, DM, matrix, solver, symbolic factorisation), solve every load case with
/// alpha tuned to its target, and build the stored representations (mesh fields, point cloud,
/// grids). A failing load case is data (status 0, reason, iterations; zero fields, never NaN).
#include <mpi.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>

#include "hypershape/config/dataset.hpp"
#include "hypershape/core/timer.hpp"
#include "hypershape/factory/accuracy.hpp"
#include "hypershape/factory/dataset_scene.hpp"
#include "hypershape/factory/label_error.hpp"
#include "hypershape/factory/load_cases.hpp"
#include "hypershape/factory/shape_pipeline.hpp"
#include "hypershape/factory/solve_counters.hpp"
#include "hypershape/geometry/boundary.hpp"
#include "hypershape/io/dataset_shard.hpp"
#include "hypershape/physics/problem.hpp"
#include "hypershape/solver/tangent.hpp"

namespace hypershape::factory {

struct ShapeJobResult {
  io::ShardShape entry;      ///< significant on rank 0 of the group
  SolveCounters counters;    ///< the shape's load cases: outcomes and solver work
  LabelErrorSummary label_error;  ///< the estimates of its converged load cases (if asked for)
  AccuracySummary accuracy;       ///< the accuracy ladder's choice and cost (config accuracy:)
  std::int64_t n_dofs = 0;
  /// shape (draw + boundary + checks), mesh, setup, solve (first nonlinear solve of each load
  /// case), alpha_search (the further solves), representations, gather.
  core::PhaseTimes times;
};

/// Collective over `group`. `base` is load_base(config.shapes). `on_load(converged)` runs on
/// every rank of the group after each load case (progress). Never throws for a shape or a
/// load case that fails (both are recorded); throws for programming or I/O errors only.
ShapeJobResult run_shape(MPI_Comm group, const config::DatasetConfig& config,
                         const std::optional<geometry::Boundary>& base, std::int64_t shape_id,
                         const std::function<void(bool)>& on_load = {});

}  // namespace hypershape::factory
