#pragma once
/// The `solver:` and `petsc:` blocks, shared by scenes and dataset configs (internal).
#include <string>
#include <utility>
#include <vector>

#include "hypershape/solver/nonlinear.hpp"
#include "yaml_block.hpp"

namespace hypershape::config {

/// Reads rtol, max_newton, max_increments, target_rtol, control (displacement | load),
/// path_rtol, newton_budget, fallback over the defaults in `out`.
void parse_solver_block(const YamlBlock& block, solver::SolverOptions& out);
/// Reads any PETSc options (key without the dash: scalar value or empty).
void parse_petsc_block(const YamlBlock& block, std::vector<std::pair<std::string, std::string>>& out);

}  // namespace hypershape::config
