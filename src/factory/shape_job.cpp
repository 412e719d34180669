#include "hypershape/factory/shape_job.hpp"

#include <fmt/format.h>

#include <cmath>
#include <map>
#include <numeric>

#include "hypershape/core/error.hpp"
#include "hypershape/factory/load_cases.hpp"
#include "hypershape/factory/shape_pipeline.hpp"
#include "hypershape/factory/shape_set.hpp"
#include "hypershape/geometry/distance.hpp"
#include "hypershape/physics/gaussian_traction.hpp"
#include "hypershape/physics/problem.hpp"
#include "hypershape/physics/registry.hpp"
#include "hypershape/sampling/grid.hpp"
#include "hypershape/sampling/mesh_sampler.hpp"
#include "hypershape/solver/nonlinear.hpp"

namespace hypershape::factory {

namespace {

using U64 = std::uint64_t;

/// Per-component (count, sum, sum of squares) of the values a shape contributes to a field,
/// merged over the train split into normalisation statistics by the index step.
class Moments {
 public:
  void add(const std::string& field, const double* v, std::size_t n, int n_comp) {
    auto& m = rows_[field];
    m.resize(std::size_t(3 * n_comp), 0.0);
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t c = i % std::size_t(n_comp);
      m[3 * c] += 1;
      m[3 * c + 1] += v[i];
      m[3 * c + 2] += v[i] * v[i];
    }
  }
  void store(std::vector<io::Array>& out) const {
    for (const auto& [name, m] : rows_)
      out.push_back({"stats/" + name, {m.size() / 3, 3}, m,
                     "per component: count, sum, sum of squares over this shape's converged values", ""});
  }

 private:
  std::map<std::string, std::vector<double>> rows_;
};

/// Nodes on the boundary facets of each kind: vertices of the facets and, for P2, the midpoints
/// of their edges (found through the cells' edges, VTK order).
void boundary_node_masks(const geometry::Boundary& b, const std::vector<int>& dirichlet_facets,
                         const std::vector<std::int64_t>& cells, int degree, std::int64_t n_nodes,
                         std::vector<std::int8_t>& dirichlet, std::vector<std::int8_t>& neumann) {
  const int d = b.dim;
  dirichlet.assign(std::size_t(n_nodes), 0);
  neumann.assign(std::size_t(n_nodes), 0);
  std::map<std::pair<std::int64_t, std::int64_t>, std::int64_t> midpoint;
  if (degree == 2) {
    static const int tri[3][3] = {{0, 1, 3}, {1, 2, 4}, {2, 0, 5}};
    static const int tet[6][3] = {{0, 1, 4}, {1, 2, 5}, {2, 0, 6}, {0, 3, 7}, {1, 3, 8}, {2, 3, 9}};
    const int per = d == 2 ? 6 : 10;
    for (std::size_t c = 0; c + std::size_t(per) <= cells.size(); c += std::size_t(per)) {
      const int n_edges = d == 2 ? 3 : 6;
      for (int e = 0; e < n_edges; ++e) {
        const int* t = d == 2 ? tri[e] : tet[e];
        auto a = cells[c + std::size_t(t[0])], z = cells[c + std::size_t(t[1])];
        midpoint[{std::min(a, z), std::max(a, z)}] = cells[c + std::size_t(t[2])];
      }
    }
  }
  std::vector<std::uint8_t> is_dirichlet(std::size_t(b.n_facets()), 0);
  for (int f : dirichlet_facets) is_dirichlet[std::size_t(f)] = 1;
  for (std::int64_t f = 0; f < b.n_facets(); ++f) {
    auto& mask = is_dirichlet[std::size_t(f)] ? dirichlet : neumann;
    const auto v = b.facet(f);
    for (int a = 0; a < d; ++a) mask[std::size_t(v[a])] = 1;
    if (degree == 2)
      for (int a = 0; a < d; ++a)
        for (int z = a + 1; z < d; ++z) {
          const std::int64_t p = v[a], q = v[z];
          auto it = midpoint.find({std::min(p, q), std::max(p, q)});
          if (it != midpoint.end()) mask[std::size_t(it->second)] = 1;
        }
  }
}

std::vector<float> to_float(const std::vector<double>& v) { return {v.begin(), v.end()}; }

bool all_finite(const std::vector<double>& v) {
  for (double x : v)
    if (!std::isfinite(x)) return false;
  return true;
}

}  // namespace

ShapeProblem make_shape_problem(MPI_Comm group, const config::DatasetConfig& cfg,
                                const ShapeSample& shape, const LoadCase& first,
                                std::optional<physics::SpaceOptions> space) {
  const int d = cfg.shapes.dim;
  std::vector<physics::EffectPtr> effects;
  effects.push_back(physics::make_neo_hookean(cfg.material.E, cfg.material.nu));
  effects.push_back(physics::make_dirichlet_patch(
      std::vector<double>(shape.dirichlet_center.begin(), shape.dirichlet_center.begin() + d),
      shape.dirichlet_radius));
  auto gt = std::make_unique<physics::GaussianTraction>(
      std::vector<double>(first.center.begin(), first.center.begin() + d),
      std::vector<double>(first.direction.begin(), first.direction.begin() + d), cfg.loads.gamma);
  ShapeProblem out;
  out.traction = gt.get();
  effects.push_back(std::move(gt));
  out.problem = std::make_unique<physics::Problem>(group, shape.mesh, std::move(effects),
                                                   space.value_or(physics::SpaceOptions{cfg.degree}));
  return out;
}

ShapeJobResult run_shape(MPI_Comm group, const config::DatasetConfig& cfg,
                         const std::optional<geometry::Boundary>& base, std::int64_t shape_id,
                         const std::function<void(bool)>& on_load) {
  ShapeJobResult out;
  int rank = 0;
  MPI_Comm_rank(group, &rank);
  const bool root = rank == 0;
  const int d = cfg.shapes.dim;
  const int n_loads = cfg.loads.count;

  // ---- the shape (every rank of the group draws the same one) ---------------------------------
  ShapeSample shape;
  {
    auto t = out.times.scope("shape");
    try {
      shape = make_shape(cfg.shapes, base, cfg.seed, shape_id);
    } catch (const std::runtime_error& e) {
      out.entry.ok = false;
      out.entry.failure = e.what();
      out.entry.shape.shape_id = shape_id;
      out.entry.shape.dim = d;
      out.entry.shape.rejected = e.what();
      out.entry.shape.numbers = {{"failed", 1}};
      out.entry.shape.source_file = source_file(cfg.shapes, shape_id);
      out.loads_failed = n_loads;
      return out;
    }
  }
  out.times.add("mesh", shape.seconds_mesh);
  out.times.add("shape", -shape.seconds_mesh);
  out.entry.shape = to_record(shape);
  for (auto it = out.entry.shape.numbers.begin(); it != out.entry.shape.numbers.end();)
    it = it->first.rfind("seconds_", 0) == 0 ? out.entry.shape.numbers.erase(it) : std::next(it);
  const auto cases = draw_load_cases(shape, cfg.loads, cfg.seed);

  // ---- the problem, set up once for all load cases --------------------------------------------
  std::unique_ptr<physics::Problem> problem;
  std::unique_ptr<solver::NonlinearSolver> nl;
  physics::GaussianTraction* traction = nullptr;
  {
    auto t = out.times.scope("setup");
    ShapeProblem sp = make_shape_problem(group, cfg, shape, cases[0]);
    problem = std::move(sp.problem);
    traction = sp.traction;
    nl = std::make_unique<solver::NonlinearSolver>(*problem, cfg.solver);
  }
  const auto& space = problem->space();
  out.n_dofs = space.n_dofs_global();

  // ---- per-shape representations (group root) -------------------------------------------------
  auto& arrays = out.entry.arrays;
  Moments moments;
  std::vector<double> nodes;
  std::vector<std::int64_t> cells;
  std::int64_t n_nodes = 0;
  std::vector<std::int8_t> dirichlet_mask, neumann_mask;
  std::unique_ptr<sampling::MeshSampler> sampler;
  std::vector<double> grid;
  const int N = cfg.representations.grid_size;
  std::uint64_t n_grid = 0;
  std::vector<std::uint64_t> grid_shape;
  if (root) {
    auto t = out.times.scope("representations");
    nodes = space.canonical_coords();
    cells = space.canonical_cells();
    n_nodes = std::int64_t(nodes.size()) / d;
    const auto per_cell = std::uint64_t(cells.size()) / std::uint64_t(shape.mesh.n_cells());
    arrays.push_back({"nodes", {U64(n_nodes), U64(d)}, nodes,
                      "finite-element nodes: mesh vertices first, then (P2) edge midpoints", "length"});
    arrays.push_back({"cells", {U64(shape.mesh.n_cells()), per_cell}, cells,
                      "cell-to-node connectivity, VTK order", ""});
    boundary_node_masks(shape.boundary, shape.dirichlet_facets, cells, cfg.degree, n_nodes, dirichlet_mask,
                        neumann_mask);
    arrays.push_back({"dirichlet_mask", {U64(n_nodes)}, dirichlet_mask, "1 on the Dirichlet patch (u = 0)", ""});
    arrays.push_back({"neumann_mask", {U64(n_nodes)}, neumann_mask, "1 on the Neumann boundary (traction)", ""});
    const geometry::SignedDistance sdf(shape.boundary);
    std::vector<std::int64_t> dfacets(shape.dirichlet_facets.begin(), shape.dirichlet_facets.end());
    const geometry::FacetSetDistance ddist(shape.boundary, dfacets);
    if (cfg.representations.point_cloud) {
      std::vector<double> s(static_cast<std::size_t>(n_nodes)), dd(static_cast<std::size_t>(n_nodes));
      sdf.evaluate(nodes, s);
      ddist.evaluate(nodes, dd);
      moments.add("sdf", s.data(), s.size(), 1);
      moments.add("dirichlet_distance", dd.data(), dd.size(), 1);
      arrays.push_back({"point_cloud/sdf", {U64(n_nodes)}, std::move(s),
                        "signed distance to the boundary at the nodes (negative inside)", "length"});
      arrays.push_back({"point_cloud/dirichlet_distance", {U64(n_nodes)}, std::move(dd),
                        "distance to the Dirichlet patch at the nodes", "length"});
    }
    if (cfg.representations.grid) {
      grid = sampling::grid_points(d, N);
      n_grid = grid.size() / std::size_t(d);
      grid_shape.assign(std::size_t(d), U64(N));
      std::vector<double> s(n_grid), dd(n_grid);
      sdf.evaluate(grid, s);
      ddist.evaluate(grid, dd);
      moments.add("grid_sdf", s.data(), s.size(), 1);
      moments.add("grid_dirichlet_distance", dd.data(), dd.size(), 1);
      arrays.push_back({"grid/sdf", grid_shape, to_float(s),
                        "signed distance on the grid over [-1, 1]^d (negative inside), numpy 'ij' order",
                        "length"});
      arrays.push_back({"grid/dirichlet_distance", grid_shape, to_float(dd),
                        "distance to the Dirichlet patch on the grid (0 on the patch, never negative)",
                        "length"});
      sampler = std::make_unique<sampling::MeshSampler>(d, cfg.degree, nodes, cells, shape.boundary, sdf, grid);
      const auto inside = sampler->inside();
      arrays.push_back({"grid/inside", grid_shape, std::vector<std::int8_t>(inside.begin(), inside.end()),
                        "1 where the grid point is in the body", ""});
    }
  }

  // ---- load cases -----------------------------------------------------------------------------
  std::vector<std::int8_t> status(std::size_t(n_loads), 0);
  std::vector<std::string> reasons(static_cast<std::size_t>(n_loads));
  std::vector<double> alpha(std::size_t(n_loads), 0), target(static_cast<std::size_t>(n_loads)), max_u(std::size_t(n_loads), 0),
      min_det(std::size_t(n_loads), 0), normaliser(std::size_t(n_loads), 0), p_n(std::size_t(n_loads * d)),
      g(std::size_t(n_loads * d));
  std::vector<std::int64_t> newton(std::size_t(n_loads), 0), solves(std::size_t(n_loads), 0),
      failed_inc(std::size_t(n_loads), 0), recovery(std::size_t(n_loads), 0);
  std::vector<double> displacement, node_traction;
  std::vector<float> grid_u, grid_t;
  if (root) {
    displacement.assign(std::size_t(n_loads * n_nodes * d), 0.0);
    if (cfg.representations.point_cloud) node_traction.assign(displacement.size(), 0.0);
    if (cfg.representations.grid) {
      grid_u.assign(std::size_t(n_loads) * n_grid * std::size_t(d), 0.0f);
      grid_t.assign(grid_u.size(), 0.0f);
    }
  }
  for (int l = 0; l < n_loads; ++l) {
    const LoadCase& lc = cases[std::size_t(l)];
    const auto L = std::size_t(l);
    target[L] = lc.target;
    for (int k = 0; k < d; ++k) {
      p_n[L * std::size_t(d) + std::size_t(k)] = lc.center[std::size_t(k)];
      g[L * std::size_t(d) + std::size_t(k)] = lc.direction[std::size_t(k)];
    }
    solver::TargetResult r;
    std::string failure;
    try {
      traction->set(std::vector<double>(lc.center.begin(), lc.center.begin() + d),
                    std::vector<double>(lc.direction.begin(), lc.direction.begin() + d));
      {
        auto t = out.times.scope("setup");
        problem->reassemble_load();
      }
      normaliser[L] = traction->normaliser();
      nl->reset();
      r = nl->solve_for_target(lc.target);
      out.times.add("solve", r.seconds_first_solve);
      out.times.add("alpha_search", r.seconds_total - r.seconds_first_solve);
    } catch (const std::exception& e) {
      failure = std::string("error: ") + e.what();
    }
    newton[L] = r.newton_iterations;
    solves[L] = r.solves;
    failed_inc[L] = r.failed_increments;
    recovery[L] = r.recovery_iterations;
    out.recovery_iterations += r.recovery_iterations;
    out.newton_iterations += r.newton_iterations;
    out.linear += r.linear;
    out.solves += r.solves;
    out.failed_increments += r.failed_increments;
    bool ok = failure.empty() && r.converged;
    physics::NodalField u;
    {
      auto t = out.times.scope("gather");
      const double m = problem->max_displacement(nl->solution());
      const double j = problem->min_det_f(nl->solution());
      u = problem->gather(nl->solution());
      if (ok && !(std::isfinite(m) && std::isfinite(j))) ok = false, failure = "non-finite displacement";
      if (ok && !(j > 0)) ok = false, failure = "inverted cells (min det F <= 0)";
      if (ok) max_u[L] = m, min_det[L] = j, alpha[L] = r.alpha;
    }
    if (root && ok && !all_finite(u.values)) ok = false, failure = "non-finite displacement";
    MPI_Bcast(&ok, 1, MPI_CXX_BOOL, 0, group);
    status[L] = ok ? 1 : 0;
    reasons[L] = ok ? r.reason : (failure.empty() ? r.reason : failure);
    (ok ? out.loads_ok : out.loads_failed) += 1;
    if (on_load) on_load(ok);
    if (!ok) {
      max_u[L] = min_det[L] = alpha[L] = 0;  // the fields stay zero: never NaN
      continue;
    }
    if (!root) continue;
    auto t = out.times.scope("representations");
    const std::size_t off = L * std::size_t(n_nodes * d);
    std::copy(u.values.begin(), u.values.end(), displacement.begin() + std::ptrdiff_t(off));
    moments.add("displacement", u.values.data(), u.values.size(), d);
    if (cfg.representations.point_cloud) {
      for (std::int64_t n = 0; n < n_nodes; ++n) {
        if (!neumann_mask[std::size_t(n)]) continue;
        double tv[3];
        traction->value(&nodes[std::size_t(n * d)], tv);
        for (int k = 0; k < d; ++k) node_traction[off + std::size_t(n * d + k)] = alpha[L] * tv[k];
      }
      moments.add("traction", node_traction.data() + off, std::size_t(n_nodes * d), d);
    }
    if (cfg.representations.grid) {
      const std::size_t goff = L * n_grid * std::size_t(d);
      std::vector<double> gu(n_grid * std::size_t(d)), gt(n_grid * std::size_t(d));
      sampler->interpolate(u.values, d, gu);
      for (std::size_t p = 0; p < n_grid; ++p) {
        double tv[3];
        traction->value(&grid[p * std::size_t(d)], tv);
        for (int k = 0; k < d; ++k) gt[p * std::size_t(d) + std::size_t(k)] = alpha[L] * tv[k];
      }
      std::copy(gu.begin(), gu.end(), grid_u.begin() + std::ptrdiff_t(goff));
      std::copy(gt.begin(), gt.end(), grid_t.begin() + std::ptrdiff_t(goff));
      moments.add("grid_displacement", gu.data(), gu.size(), d);
      moments.add("grid_traction", gt.data(), gt.size(), d);
    }
    moments.add("alpha", &alpha[L], 1, 1);
  }

  if (root) {
    auto t = out.times.scope("representations");
    const U64 nl_ = U64(n_loads), du = U64(d);
    arrays.push_back({"loads/status", {nl_}, status, "1 converged (target reached), 0 failed (see loads/reason)", ""});
    arrays.push_back({"loads/alpha", {nl_}, alpha, "traction scale alpha = the total applied force |int t dS| (0 if failed)", "force"});
    arrays.push_back({"loads/target", {nl_}, target, "wanted max|u|", "length"});
    arrays.push_back({"loads/max_displacement", {nl_}, max_u, "achieved max over the nodes of |u| (0 if failed)", "length"});
    arrays.push_back({"loads/min_det_f", {nl_}, min_det, "min det F over the quadrature points (0 if failed)", ""});
    arrays.push_back({"loads/traction_normaliser", {nl_}, normaliser, "I_N = int_{Gamma_N} phi dS", "length^(d-1)"});
    arrays.push_back({"loads/newton_iterations", {nl_}, newton, "Newton iterations, all solves of the alpha search", ""});
    arrays.push_back({"loads/solves", {nl_}, solves, "nonlinear solves (alpha evaluations)", ""});
    arrays.push_back({"loads/failed_increments", {nl_}, failed_inc, "load increments that failed and were halved", ""});
    arrays.push_back({"loads/recovery_iterations", {nl_}, recovery,
                      "Newton iterations spent in failed (discarded) increments: the cost of recovery", ""});
    arrays.push_back({"loads/p_n", {nl_, du}, p_n, "traction centre p_N (on the Neumann boundary)", "length"});
    arrays.push_back({"loads/g", {nl_, du}, g, "traction direction g (unit vector)", ""});
    arrays.push_back({"loads/displacement", {nl_, U64(n_nodes), du}, std::move(displacement),
                      "displacement u at the nodes (zero if failed)", "length"});
    if (cfg.representations.point_cloud)
      arrays.push_back({"loads/traction", {nl_, U64(n_nodes), du}, std::move(node_traction),
                        "traction t = alpha g phi / I_N at the Neumann nodes, zero elsewhere", "force/length^(d-1)"});
    if (cfg.representations.grid) {
      std::vector<U64> s{nl_};
      s.insert(s.end(), grid_shape.begin(), grid_shape.end());
      s.push_back(du);
      arrays.push_back({"loads/grid_displacement", s, std::move(grid_u),
                        "displacement on the grid: FE interpolant inside, closest-boundary-point value outside",
                        "length"});
      arrays.push_back({"loads/grid_traction", s, std::move(grid_t),
                        "traction field alpha g phi(x - p_N) / I_N on the whole grid", "force/length^(d-1)"});
    }
    moments.store(arrays);
    out.entry.load_reasons = std::move(reasons);
  }
  return out;
}

}  // namespace hypershape::factory
