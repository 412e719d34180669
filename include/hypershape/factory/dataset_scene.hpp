#pragma once
/// A dataset's scene on one shape and load case: every distribution drawn from the
/// counter-based streams (seed, parameter, {shape id, load id + 1 or 0, effect, key}), the
/// placements the factory draws (p_D on the boundary; p_N, g per traction and load case), and
/// the problem built from it through physics::build_problem, the one problem builder.
#include <mpi.h>

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "hypershape/config/dataset.hpp"
#include "hypershape/factory/load_cases.hpp"
#include "hypershape/factory/shape_pipeline.hpp"
#include "hypershape/physics/problem.hpp"
#include "hypershape/physics/scene.hpp"

namespace hypershape::factory {

/// A drawn scene parameter, stored as "params/<label>/<key>" (per shape: one value; per load
/// case: one per load case).
struct DrawnValue {
  std::string name;   ///< "<label>/<key>", e.g. "neo_hookean/E", "gaussian_traction.1/gamma"
  bool per_load = false;
  double value = 0;
};

/// The value of the parameter `key` of effect `effect` drawn from `draw` for (shape, load).
double draw_parameter(const config::DatasetConfig& cfg, std::int64_t shape_id, int load_id, std::size_t effect,
                      const std::string& key, const physics::Draw& draw);
/// Every drawn parameter of the scene for (shape, load), in scene order (not collective).
std::vector<DrawnValue> drawn_values(const config::DatasetConfig& cfg, std::int64_t shape_id, int load_id);
/// The shape family for shape `shape_id`: the config's, with the Dirichlet radius drawn when
/// the scene draws it.
ShapeConfig shape_config(const config::DatasetConfig& cfg, std::int64_t shape_id);
/// How many copies of effect `effect` act in (shape, load) (1 without a count; the count is
/// drawn from the stream of its copy 0, key "count", and stored as params/<name>/count).
int active_copies(const config::DatasetConfig& cfg, std::int64_t shape_id, int load_id, std::size_t effect);
/// Number of gaussian_traction effects of the scene, copies included (placements per load case).
int n_tractions(const config::DatasetConfig& cfg);
/// The scene resolved for `shape` and load case `lc` (not collective).
std::vector<physics::ResolvedEffect> resolve_scene(const config::DatasetConfig& cfg, const ShapeSample& shape,
                                                   const LoadCase& lc);

/// The dataset's problem on one shape, set to a load case.
struct ShapeProblem {
  std::unique_ptr<physics::Problem> problem;
  /// Moves every load effect to load case `lc` (its draws and placements) and reassembles the
  /// loads, keeping mesh, matrix and factorisations. Collective over the problem's group.
  void set_load_case(const config::DatasetConfig& cfg, const ShapeSample& shape, const LoadCase& lc);
};
/// Collective over `group`. `space`: the discretisation (default: the config's degree).
ShapeProblem make_shape_problem(MPI_Comm group, const config::DatasetConfig& cfg, const ShapeSample& shape,
                                const LoadCase& first, std::optional<physics::SpaceOptions> space = std::nullopt);

}  // namespace hypershape::factory
