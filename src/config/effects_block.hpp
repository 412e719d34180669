#pragma once
/// The `effects:` block shared by scene files and dataset configs (internal to src/config/).
#include "hypershape/physics/scene.hpp"
#include "yaml_block.hpp"

namespace hypershape::config {

/// Parses `effects:` (a mapping of effect names to a parameter mapping or a list of them).
/// Numeric parameters may be distributions when `allow_draws` (dataset configs). Effect names
/// and their own keys are checked later, when the effects are built (physics::build_effects).
physics::SceneSpec parse_effects(const YamlBlock& block, bool allow_draws);

}  // namespace hypershape::config
