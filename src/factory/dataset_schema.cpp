#include "hypershape/factory/dataset_schema.hpp"

namespace hypershape::factory {

const std::vector<SchemaEntry>& shard_schema() {
  static const std::vector<SchemaEntry> table = {
      {"nodes", "n x d", "shape", "length", "finite-element nodes: mesh vertices first, then (P2) edge midpoints"},
      {"cells", "m x k", "shape", "", "cell-to-node connectivity, VTK order"},
      {"dirichlet_mask", "n", "shape", "", "1 on the Dirichlet patch (u = 0)"},
      {"neumann_mask", "n", "shape", "", "1 on the Neumann boundary (traction)"},
      {"point_cloud/sdf", "n", "shape", "length", "signed distance to the boundary at the nodes (negative inside)"},
      {"point_cloud/dirichlet_distance", "n", "shape", "length", "distance to the Dirichlet patch at the nodes"},
      {"grid/sdf", "N^d", "shape", "length",
       "signed distance on the grid over [-1, 1]^d (negative inside), numpy 'ij' order"},
      {"grid/dirichlet_distance", "N^d", "shape", "length",
       "distance to the Dirichlet patch on the grid (0 on the patch, never negative)"},
      {"grid/inside", "N^d", "shape", "", "1 where the grid point is in the body"},
      {"loads/status", "L", "load case", "", "1 converged (target reached), 0 failed (see loads/reason)"},
      {"loads/alpha", "L", "load case", "force",
       "traction scale alpha = the total applied force |int t dS| (0 if failed)"},
      {"loads/target", "L", "load case", "length", "wanted max|u|"},
      {"loads/max_displacement", "L", "load case", "length", "achieved max over the nodes of |u| (0 if failed)"},
      {"loads/min_det_f", "L", "load case", "", "min det F over the quadrature points (0 if failed)"},
      {"loads/error_estimate_rel_l2", "L", "load case", "",
       "a posteriori estimate of ||u - u_h||_L2 / ||u||_L2 (two-level, docs/ACCURACY.md; 0 if failed, -1: no estimate)"},
      {"loads/error_estimate_max_u", "L", "load case", "",
       "estimated relative error of max|u| at the stored alpha, signed (> 0: u_h too small; 0 if failed, -1: no estimate)"},
      {"loads/error_estimate_alpha", "L", "load case", "",
       "estimated relative error of alpha for the stored target, signed (0 if failed, -1: no estimate)"},
      {"loads/accuracy_level", "L", "load case", "",
       "accuracy ladder level the label was solved at (datasets asked for by accuracy; shape attribute accuracy_level: the stored mesh's)"},
      {"loads/accuracy_tried", "L", "load case", "", "highest accuracy ladder level the load case was solved at"},
      {"loads/traction_normaliser", "L", "load case", "length^(d-1)", "I_N = int_{Gamma_N} phi dS"},
      {"loads/newton_iterations", "L", "load case", "", "Newton iterations, all solves of the alpha search"},
      {"loads/solves", "L", "load case", "", "nonlinear solves (alpha evaluations)"},
      {"loads/failed_increments", "L", "load case", "", "load increments that failed and were halved"},
      {"loads/recovery_iterations", "L", "load case", "",
       "Newton iterations spent in failed (discarded) increments: the cost of recovery"},
      {"loads/p_n", "L x d", "load case", "length", "traction centre p_N (on the Neumann boundary)"},
      {"loads/g", "L x d", "load case", "", "traction direction g (unit vector)"},
      {"loads/displacement", "L x n x d", "load case", "length", "displacement u at the nodes (zero if failed)"},
      {"loads/grid_displacement", "L x N^d x d", "load case", "length",
       "displacement on the grid: FE interpolant inside, closest-boundary-point value outside"},
      {"loads/traction", "L x n x d", "load case", "force/length^(d-1)",
       "traction t = alpha g phi / I_N at the Neumann nodes, zero elsewhere"},
      {"loads/grid_traction", "L x N^d x d", "load case", "force/length^(d-1)",
       "traction field alpha g phi(x - p_N) / I_N on the whole grid"},
      {"loads/body_force", "L x n x d", "load case", "force/length^d",
       "body force per unit reference volume at the nodes (times alpha if scaled)"},
      {"loads/grid_body_force", "L x N^d x d", "load case", "force/length^d",
       "body force per unit reference volume on the whole grid (times alpha if scaled)"},
      {"loads/pressure", "L x n x 1", "load case", "force/length^(d-1)",
       "pressure p (times alpha if scaled) at the Neumann nodes of its region, zero elsewhere"},
      {"loads/grid_pressure", "L x N^d x 1", "load case", "force/length^(d-1)",
       "pressure p (times alpha if scaled) at the grid points inside its region"},
      {"loads/modulus", "L x n x 1", "load case", "",
       "modulus field m(x) = E(x) / E of the material at the nodes (the same for every load case)"},
      {"loads/grid_modulus", "L x N^d x 1", "load case", "", "modulus field m(x) on the whole grid"},
      {"params/gaussian_traction.<k>/center", "L x d", "load case", "length",
       "traction centre (on the Neumann boundary) of traction k >= 1"},
      {"params/gaussian_traction.<k>/direction", "L x d", "load case", "",
       "traction direction (unit vector) of traction k >= 1"},
      {"params/<label>/<key>", "1 or L", "shape or load case", "",
       "a drawn scene parameter: one value per shape (sample: shape) or one per load case (sample: load)"},
      {"stats/<field>", "c x 3", "shape", "",
       "per component: count, sum, sum of squares over this shape's converged values"},
  };
  return table;
}

namespace {

/// `name` matches `pattern` where each "<...>" stands for one or more characters other than '/'.
bool matches(std::string_view pattern, std::string_view name) {
  while (!pattern.empty()) {
    if (pattern.front() != '<') {
      if (name.empty() || name.front() != pattern.front()) return false;
      pattern.remove_prefix(1), name.remove_prefix(1);
      continue;
    }
    pattern.remove_prefix(pattern.find('>') + 1);
    std::size_t n = 0;
    while (n < name.size() && name[n] != '/' && (pattern.empty() || name[n] != pattern.front())) ++n;
    if (n == 0) return false;
    name.remove_prefix(n);
  }
  return name.empty();
}

}  // namespace

const SchemaEntry& schema_entry(const std::string& name) {
  for (const auto& e : shard_schema())
    if (e.name == name) return e;
  for (const auto& e : shard_schema())
    if (e.name.find('<') != std::string_view::npos && matches(e.name, name)) return e;
  throw std::logic_error("dataset array '" + name + "' is not in the shard schema (factory/dataset_schema.cpp)");
}

}  // namespace hypershape::factory
