#pragma once
/// The load cases of one shape (seed paper, section 3.2): p_N uniform on the Neumann boundary
/// (boundary minus the Dirichlet patch, by length / area), g uniform on the unit sphere, and
/// targets covering [target_min, target_max] by stratified sampling: the range is cut into
/// `count` equal strata, a per-shape permutation assigns one stratum to each load id, and the
/// target is uniform within it. Every draw is a pure function of (seed, shape id, load id).
#include <array>
#include <cstdint>
#include <vector>

#include "hypershape/config/dataset.hpp"
#include "hypershape/factory/shape_pipeline.hpp"

namespace hypershape::factory {

struct LoadCase {
  int load_id = 0;
  std::array<double, 3> center{};     ///< p_N, on the Neumann boundary
  std::array<double, 3> direction{};  ///< g, |g| = 1
  double target = 0;                  ///< wanted max|u|
  /// Further tractions of the scene (gaussian_traction 1, 2, ...): centre and direction drawn
  /// like the first, from the stream (seed, traction, {shape id, load id, k}).
  std::vector<std::array<double, 3>> more_centers, more_directions;
};

/// All `loads.count` load cases of `shape`, each with `n_tractions` traction placements.
/// Throws std::invalid_argument if the shape has no Neumann boundary.
std::vector<LoadCase> draw_load_cases(const ShapeSample& shape, const config::LoadsConfig& loads,
                                      std::uint64_t seed, int n_tractions = 1);

}  // namespace hypershape::factory
