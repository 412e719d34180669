#include "solver_block.hpp"

namespace hypershape::config {

void parse_solver_block(const YamlBlock& sol, solver::SolverOptions& s) {
  if (sol.has("rtol")) s.rtol = sol.number("rtol");
  if (!(s.rtol > 0 && s.rtol < 1)) sol.fail("rtol", "must be in (0, 1)");
  if (sol.has("max_newton")) s.max_newton = int(sol.integer("max_newton"));
  if (s.max_newton < 1) sol.fail("max_newton", "must be >= 1");
  if (sol.has("factor_reuse")) s.tangent.reuse = sol.boolean("factor_reuse");
  if (sol.has("krylov_budget")) s.tangent.krylov_budget = int(sol.integer("krylov_budget"));
  if (s.tangent.krylov_budget < 0 || s.tangent.krylov_budget > 100000)
    sol.fail("krylov_budget", "must be in [0, 100000] (Krylov iterations per factorisation; 0: by dimension)");
  if (sol.has("krylov_rtol")) s.tangent.krylov_rtol = sol.number("krylov_rtol");
  if (!(s.tangent.krylov_rtol > 0 && s.tangent.krylov_rtol < 1)) sol.fail("krylov_rtol", "must be in (0, 1)");
  if (sol.has("max_increments")) s.max_increments = int(sol.integer("max_increments"));
  if (s.max_increments < 1) sol.fail("max_increments", "must be >= 1");
  if (sol.has("target_rtol")) s.target_rtol = sol.number("target_rtol");
  if (!(s.target_rtol > 0 && s.target_rtol < 1)) sol.fail("target_rtol", "must be in (0, 1)");
  if (sol.has("control")) {
    const std::string c = sol.text("control");
    if (c == "displacement") s.control = solver::Control::displacement;
    else if (c == "load") s.control = solver::Control::load;
    else sol.fail("control", "must be displacement or load");
  }
  if (sol.has("path_rtol")) s.path_rtol = sol.number("path_rtol");
  if (!(s.path_rtol > 0 && s.path_rtol < 1)) sol.fail("path_rtol", "must be in (0, 1)");
  if (sol.has("newton_budget")) s.newton_budget = int(sol.integer("newton_budget"));
  if (s.newton_budget < 1) sol.fail("newton_budget", "must be >= 1");
  if (sol.has("fallback")) s.fallback = sol.boolean("fallback");
  if (sol.has("step_growth")) s.step_growth = sol.number("step_growth");
  if (!(s.step_growth == 0 || (s.step_growth >= 1 && s.step_growth <= 4)))
    sol.fail("step_growth", "must be 0 (by dimension: 1.5 in 2D, 2 in 3D) or in [1, 4] (the next increment's length "
                            "after an easy one, as a multiple of the last)");
  if (sol.has("abandon_off_path")) s.abandon_off_path = sol.boolean("abandon_off_path");
  if (sol.has("absolute_pivots")) s.absolute_pivots = sol.boolean("absolute_pivots");
  if (sol.has("arc_length_rescue")) s.arc_length_rescue = sol.boolean("arc_length_rescue");
  if (sol.has("retry_from_rest")) s.retry_from_rest = sol.boolean("retry_from_rest");
  if (sol.has("p1_start")) s.p1_start = sol.boolean("p1_start");
  if (sol.has("local_relaxation")) s.local_relaxation = sol.boolean("local_relaxation");
  if (sol.has("predictor")) {
    const std::string p = sol.text("predictor");
    if (p == "second_order") s.predictor = solver::Predictor::second_order;
    else if (p == "tangent") s.predictor = solver::Predictor::tangent;
    else sol.fail("predictor", "must be second_order or tangent");
  }
  if (sol.has("corrector")) {
    const std::string c = sol.text("corrector");
    if (c == "chebyshev") s.corrector = solver::Corrector::chebyshev;
    else if (c == "newton") s.corrector = solver::Corrector::newton;
    else sol.fail("corrector", "must be chebyshev (the last increment's step plus its second-order term) or newton");
  }
  if (sol.has("branch_switches")) s.branch_switches = int(sol.integer("branch_switches"));
  if (s.branch_switches < 0 || s.branch_switches > 10) sol.fail("branch_switches", "must be in [0, 10]");
  if (sol.has("linear")) {
    const auto l = solver::linear_solver_from_string(sol.text("linear"));
    if (!l) sol.fail("linear", "must be auto, direct, gamg or hypre");
    s.tangent.linear = *l;
  }
  if (sol.has("factor_precision")) {
    const std::string f = sol.text("factor_precision");
    if (f != "double" && f != "single") sol.fail("factor_precision", "must be double or single");
    s.tangent.single_factor = f == "single";
  }
  if (sol.has("linear_auto_dofs")) s.tangent.auto_dofs = sol.integer("linear_auto_dofs");
  if (s.tangent.auto_dofs < 1) sol.fail("linear_auto_dofs", "must be >= 1 (unknowns from which auto picks gamg in 3D)");
  if (s.tangent.reuse && (s.tangent.linear == solver::LinearSolver::gamg || s.tangent.linear == solver::LinearSolver::hypre))
    sol.fail("factor_reuse", "must be false with linear: gamg or hypre (a kept factor is the direct solver's)");
  sol.allowed("rtol, max_newton, factor_reuse, krylov_budget, krylov_rtol, max_increments, target_rtol, control, path_rtol, newton_budget, fallback, "
              "branch_switches, step_growth, abandon_off_path, absolute_pivots, arc_length_rescue, retry_from_rest, p1_start, local_relaxation, predictor, corrector, linear, linear_auto_dofs, factor_precision");
  sol.check_all_used();
}

void parse_petsc_block(const YamlBlock& petsc, std::vector<std::pair<std::string, std::string>>& out) {
  if (!petsc.node() || !petsc.node().IsMap()) return;
  for (const auto& kv : petsc.node()) {
    const std::string k = kv.first.Scalar();
    petsc.get(k);
    if (k.empty() || k.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_") !=
                         std::string::npos || k.front() == '_')
      petsc.fail(k, "not a PETSc option name: letters, digits and '_', without the leading dash (snes_monitor)");
    if (!kv.second.IsNull() && !kv.second.IsScalar()) petsc.fail(k, "must be a scalar value");
    out.emplace_back("-" + k, kv.second.IsNull() ? "" : kv.second.Scalar());
  }
}

}  // namespace hypershape::config
