#include <fmt/format.h>

#include <algorithm>

#include "hypershape/config/dataset.hpp"
#include "hypershape/config/scene.hpp"

namespace hypershape::config {

namespace {

std::string num(double v) { return fmt::format("{:.17g}", v); }

std::string shapes_text(const DatasetConfig& c) {
  const auto& s = c.shapes;
  std::string t = fmt::format("shapes:\n  count: {}\n  dim: {}\n  base: {}\n  base_file: '{}'\n  base_dir: '{}'\n",
                              c.n_shapes, s.dim, s.base, s.base_file, s.base_dir);
  for (const auto& f : s.base_files) t += fmt::format("  - file: '{}'\n", f);
  t += "  steps: [";
  for (const auto& st : s.deformation.steps) t += fmt::format("[{}, {}], ", num(st.sigma), num(st.m));
  t += "]\n";
  t += fmt::format("  velocity_unit: {}\n  nodes_per_sigma: {}\n  margin_sigmas: {}\n",
                   num(s.deformation.velocity_unit), num(s.deformation.nodes_per_sigma),
                   num(s.deformation.margin_sigmas));
  t += fmt::format("  h: {}\n  mesh_h: {}\n  dirichlet_radius: {}\n  max_turn_deg: {}\n  min_feature_fraction: {}\n",
                   num(s.h), num(s.mesh_h), num(s.dirichlet_radius), num(s.max_turn_deg),
                   num(s.min_feature_fraction));
  // Written only when set, so that the identity of every config without them is unchanged.
  if (s.surface_h > 0) t += fmt::format("  surface_h: {}\n", num(s.surface_h));
  if (s.rim_size > 0) t += fmt::format("  rim_size: {}\n", num(s.rim_size));
  t += fmt::format("  size_grading: {}\n  max_attempts: {}\n  quality: [{}, {}]\n", num(s.size_grading),
                   s.max_attempts, num(s.quality.min_angle_deg), num(s.quality.min_shape));
  return t;
}

std::string solver_text(const solver::SolverOptions& s) {
  // The linear solver joins the identity only when it is not the default (so that datasets
  // made before the key existed keep theirs): AMG and a factorisation agree to the tolerance,
  // not bit for bit.
  const solver::TangentOptions defaults;
  std::string linear;
  if (s.tangent.linear != defaults.linear || s.tangent.auto_dofs != defaults.auto_dofs)
    linear = fmt::format("  linear: {}\n  linear_auto_dofs: {}\n", solver::to_string(s.tangent.linear),
                         s.tangent.auto_dofs);
  return fmt::format(
      "solver:\n  rtol: {}\n  atol: {}\n  control: {}\n  path_rtol: {}\n  newton_budget: {}\n  fallback: {}\n"
      "  branch_switches: {}\n  max_halvings: {}\n  max_newton: {}\n  factor_reuse: {}\n  krylov_budget: {}\n"
      "  krylov_rtol: {}\n  max_increments: {}\n  min_increment: {}\n  guard: {}\n  target_rtol: {}\n"
      "  max_target_solves: {}\n",
      num(s.rtol), num(s.atol), int(s.control), num(s.path_rtol), s.newton_budget, s.fallback, s.branch_switches,
      s.max_halvings, s.max_newton, s.tangent.reuse, s.tangent.krylov_budget, num(s.tangent.krylov_rtol),
      s.max_increments, num(s.min_increment), s.guard, num(s.target_rtol), s.max_target_solves) +
         linear +
         (s.step_growth != solver::SolverOptions{}.step_growth ? "  step_growth: " + num(s.step_growth) + "\n" : "") +
         (s.abandon_off_path ? "  abandon_off_path: true\n" : "") +  // likewise only when asked for
         (s.absolute_pivots ? "  absolute_pivots: true\n" : "") +  // likewise (2026-11-30)
         (s.arc_length_rescue ? "  arc_length_rescue: true\n" : "") +  // only when turned on (the default since 2026-11-28)
         (s.retry_from_rest ? "" : "  retry_from_rest: false\n") +
         (s.p1_start ? "" : "  p1_start: false\n") +  // the default (2026-11-29): older identities unchanged
         (s.predictor == solver::Predictor::second_order ? "" : "  predictor: tangent\n") +  // likewise
         (s.corrector == solver::Corrector::chebyshev ? "" : "  corrector: newton\n") +  // likewise (2026-11-29)
         (s.local_relaxation ? "" : "  local_relaxation: false\n") +  // the default (2026-11-29): older identities unchanged
         (s.tangent.single_factor ? "  factor_precision: single\n" : "");
}

}  // namespace

std::string canonical_text(const DatasetConfig& c) {
  std::string t = fmt::format("# hypershape dataset identity (every resolved value)\nname: {}\nseed: {}\n", c.name,
                              c.seed);
  t += shapes_text(c);
  t += fmt::format("loads:\n  count: {}\n  target: [{}, {}]\n", c.loads.count, num(c.loads.target_min),
                   num(c.loads.target_max));
  t += "scene:\n" + effects_yaml(c.scene) + "\n";
  const auto& r = c.representations;
  t += fmt::format("degree: {}\nrepresentations: [{}, {}, {}]\nsplit: [{}, {}, {}]\nshard_size: {}\n", c.degree,
                   r.point_cloud, r.grid, r.grid_size, num(c.split.train), num(c.split.val), num(c.split.test),
                   c.shard_size);
  if (c.quadrature) t += fmt::format("quadrature: {}\n", c.quadrature);  // only when given, as below
  if (r.error_estimate) t += "error_estimate: true\n";  // only when asked for: older datasets keep their identity
  if (const auto& a = c.accuracy; a.enabled())  // likewise
    t += fmt::format("accuracy: [{}, {}, {}{}{}{}]\n", num(a.rel_l2), a.max_level, num(a.exceed_share),
                     a.start_from_coarse ? ", coarse" : "",  // the default (rest): older identities unchanged
                     a.resolve_newton_budget ? fmt::format(", budget {}", a.resolve_newton_budget) : "",  // likewise
                     a.resolve_retries ? "" : ", one try");  // likewise
  t += solver_text(c.solver);
  // PETSc options in a fixed order (the order they are written in does not matter).
  auto petsc = c.petsc;
  std::sort(petsc.begin(), petsc.end());
  t += "petsc:\n";
  for (const auto& [k, v] : petsc) t += fmt::format("  '{}': '{}'\n", k, v);
  return t;
}

}  // namespace hypershape::config
