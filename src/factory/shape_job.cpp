#include "hypershape/factory/shape_job.hpp"
#include "hypershape/mesh/reference_cell.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>

#include "hypershape/core/error.hpp"
#include "hypershape/factory/dataset_schema.hpp"
#include "hypershape/factory/label_error.hpp"
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
      out.push_back(schema_array("stats/" + name, {m.size() / 3, 3}, m));
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
    const auto per = std::size_t(mesh::nodes_per_cell(d, 2));
    const auto edges = mesh::edges(d);
    for (std::size_t c = 0; c + per <= cells.size(); c += per)
      for (std::size_t e = 0; e < edges.size(); ++e) {
        auto a = cells[c + std::size_t(edges[e].first)], z = cells[c + std::size_t(edges[e].second)];
        midpoint[{std::min(a, z), std::max(a, z)}] = cells[c + std::size_t(d + 1) + e];
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

/// The input channels the scene's effects bring (traction, body force, ...), per load case at
/// the nodes ("loads/<name>", surface channels at the Neumann nodes only) and on the grid
/// ("loads/grid_<name>"), each summed over its effects, a scaled effect times alpha. A channel
/// no effect brings is neither allocated nor stored.
class Channels {
 public:
  Channels(const physics::Problem& p, const config::RepresentationsConfig& rep) : rep_(rep) {
    for (std::size_t i = 0; i < p.effects().size(); ++i) {
      const std::string c = p.effects()[i]->channel();
      if (c.empty()) continue;
      auto it = std::find_if(channels_.begin(), channels_.end(), [&](const Channel& x) { return x.name == c; });
      if (it == channels_.end())
        it = channels_.insert(channels_.end(), Channel{c, p.effects()[i]->channel_components(p.space().dim()), {}, {}, {}});
      it->effects.push_back(i);
    }
  }
  /// `node_points`: load cases x nodes, `grid_points`: load cases x grid points.
  void allocate(std::size_t node_points, std::size_t grid_points) {
    for (auto& c : channels_) {
      if (rep_.point_cloud) c.nodes.assign(node_points * std::size_t(c.components), 0.0);
      if (rep_.grid) c.grid.assign(grid_points * std::size_t(c.components), 0.0f);
    }
  }
  /// Load case L (group root).
  void fill(const physics::Problem& p, std::size_t L, double alpha, int d, const std::vector<double>& nodes,
            const std::vector<std::int8_t>& neumann, const std::vector<double>& grid, Moments& moments) {
    const std::size_t n_nodes = nodes.size() / std::size_t(d), n_grid = grid.size() / std::size_t(d);
    for (auto& c : channels_) {
      const auto nc = std::size_t(c.components);
      if (rep_.point_cloud) {
        double* v = c.nodes.data() + L * n_nodes * nc;
        add(p, c, alpha, d, nodes, &neumann, v);
        moments.add(c.name, v, n_nodes * nc, c.components);
      }
      if (rep_.grid) {
        std::vector<double> g(n_grid * nc, 0.0);
        add(p, c, alpha, d, grid, nullptr, g.data());
        std::copy(g.begin(), g.end(), c.grid.begin() + std::ptrdiff_t(L * g.size()));
        moments.add("grid_" + c.name, g.data(), g.size(), c.components);
      }
    }
  }
  void store(std::vector<io::Array>& arrays, std::uint64_t n_loads, std::uint64_t n_nodes,
             const std::vector<std::uint64_t>& grid_shape) {
    for (auto& c : channels_) {
      const auto d = std::uint64_t(c.components);
      if (rep_.point_cloud) {
        arrays.push_back(schema_array("loads/" + c.name, {n_loads, n_nodes, d}, std::move(c.nodes)));
      }
      if (rep_.grid) {
        std::vector<std::uint64_t> s{n_loads};
        s.insert(s.end(), grid_shape.begin(), grid_shape.end());
        s.push_back(d);
        arrays.push_back(schema_array("loads/grid_" + c.name, s, std::move(c.grid)));
      }
    }
  }

 private:
  struct Channel {
    std::string name;
    int components;
    std::vector<std::size_t> effects;
    std::vector<double> nodes;
    std::vector<float> grid;
  };
  /// Adds the channel's value at `points` (d coordinates each) into v (c.components each);
  /// `neumann` (nodes): surface channels there only. A load's channel is scaled like its load; a
  /// material's (a modulus field) is not.
  static void add(const physics::Problem& p, const Channel& c, double alpha, int d, const std::vector<double>& points,
                  const std::vector<std::int8_t>* neumann, double* v) {
    const std::size_t n = points.size() / std::size_t(d);
    for (std::size_t i : c.effects) {
      const physics::Effect& e = *p.effects()[i];
      if (!e.active()) continue;
      const double scale = e.has_load() && e.scaled() ? alpha : 1.0;
      const auto nc = std::size_t(c.components);
      for (std::size_t a = 0; a < n; ++a) {
        if (neumann && e.channel_on_boundary() && !(*neumann)[a]) continue;
        double t[3] = {0, 0, 0};
        e.channel_value(&points[a * std::size_t(d)], t);
        for (std::size_t k = 0; k < nc; ++k) v[a * nc + k] += scale * t[k];
      }
    }
  }
  config::RepresentationsConfig rep_;
  std::vector<Channel> channels_;
};

/// The scene's drawn parameters ("params/<label>/<key>": one value per shape, or one per load
/// case) and the placements of tractions after the first ("params/gaussian_traction.k/center",
/// ".../direction"; the first's are loads/p_n and loads/g).
class DrawnParams {
 public:
  DrawnParams(const config::DatasetConfig& cfg, std::int64_t shape_id, int n_loads)
      : cfg_(cfg), shape_id_(shape_id), n_loads_(n_loads) {}
  void add(const LoadCase& lc) {
    for (const auto& v : drawn_values(cfg_, shape_id_, lc.load_id))
      if (v.per_load || lc.load_id == 0) values_[v.name].push_back(v.value);
    const auto tractions = cfg_.scene.find("gaussian_traction");
    for (std::size_t k = 0; k < lc.more_centers.size(); ++k) {
      const auto& given = cfg_.scene.effects[tractions.at(k + 1)].params;  // a fixed one is in the scene
      const std::string label = "gaussian_traction." + std::to_string(k + 1);
      if (!given.count("center")) append(placements_[label + "/center"], lc.more_centers[k]);
      if (!given.count("direction")) append(placements_[label + "/direction"], lc.more_directions[k]);
    }
  }
  void store(std::vector<io::Array>& arrays) {
    for (auto& [name, v] : values_) {
      const auto n = std::uint64_t(v.size());  // before v is moved
      arrays.push_back(schema_array("params/" + name, {n}, std::move(v)));
    }
    for (auto& [name, v] : placements_)
      arrays.push_back(
          schema_array("params/" + name, {std::uint64_t(n_loads_), std::uint64_t(cfg_.shapes.dim)}, std::move(v)));
  }

 private:
  void append(std::vector<double>& to, const std::array<double, 3>& v) const {
    to.insert(to.end(), v.begin(), v.begin() + cfg_.shapes.dim);
  }
  const config::DatasetConfig& cfg_;
  std::int64_t shape_id_;
  int n_loads_;
  std::map<std::string, std::vector<double>> values_, placements_;
};

/// I_N of the scene's first Gaussian traction (0 if none).
double first_normaliser(const physics::Problem& p) {
  for (const auto& e : p.effects())
    if (const auto* t = dynamic_cast<const physics::GaussianTraction*>(e.get())) return t->normaliser();
  return 0.0;
}

}  // namespace

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
      shape = make_shape(shape_config(cfg, shape_id), base, cfg.seed, shape_id);
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
  const auto cases = draw_load_cases(shape, cfg.loads, cfg.seed, n_tractions(cfg));

  // ---- the problem, set up once for all load cases --------------------------------------------
  ShapeProblem sp;
  std::unique_ptr<solver::NonlinearSolver> nl;
  {
    auto t = out.times.scope("setup");
    sp = make_shape_problem(group, cfg, shape, cases[0]);
    nl = std::make_unique<solver::NonlinearSolver>(*sp.problem, cfg.solver);
  }
  const physics::Problem* problem = sp.problem.get();
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
    arrays.push_back(schema_array("nodes", {U64(n_nodes), U64(d)}, nodes));
    arrays.push_back(schema_array("cells", {U64(shape.mesh.n_cells()), per_cell}, cells));
    boundary_node_masks(shape.boundary, shape.dirichlet_facets, cells, cfg.degree, n_nodes, dirichlet_mask,
                        neumann_mask);
    arrays.push_back(schema_array("dirichlet_mask", {U64(n_nodes)}, dirichlet_mask));
    arrays.push_back(schema_array("neumann_mask", {U64(n_nodes)}, neumann_mask));
    const geometry::SignedDistance sdf(shape.boundary);
    std::vector<std::int64_t> dfacets(shape.dirichlet_facets.begin(), shape.dirichlet_facets.end());
    const geometry::FacetSetDistance ddist(shape.boundary, dfacets);
    if (cfg.representations.point_cloud) {
      std::vector<double> s(static_cast<std::size_t>(n_nodes)), dd(static_cast<std::size_t>(n_nodes));
      sdf.evaluate(nodes, s);
      ddist.evaluate(nodes, dd);
      moments.add("sdf", s.data(), s.size(), 1);
      moments.add("dirichlet_distance", dd.data(), dd.size(), 1);
      arrays.push_back(schema_array("point_cloud/sdf", {U64(n_nodes)}, std::move(s)));
      arrays.push_back(schema_array("point_cloud/dirichlet_distance", {U64(n_nodes)}, std::move(dd)));
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
      arrays.push_back(schema_array("grid/sdf", grid_shape, to_float(s)));
      arrays.push_back(schema_array("grid/dirichlet_distance", grid_shape, to_float(dd)));
      sampler = std::make_unique<sampling::MeshSampler>(d, cfg.degree, nodes, cells, shape.boundary, sdf, grid);
      const auto inside = sampler->inside();
      arrays.push_back(schema_array("grid/inside", grid_shape, std::vector<std::int8_t>(inside.begin(), inside.end())));
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
  std::vector<double> displacement;
  std::vector<float> grid_u;
  Channels channels(*problem, cfg.representations);
  DrawnParams drawn(cfg, shape_id, n_loads);
  LabelErrors label_errors(n_loads);
  if (root) {
    displacement.assign(std::size_t(n_loads * n_nodes * d), 0.0);
    if (cfg.representations.grid) grid_u.assign(std::size_t(n_loads) * n_grid * std::size_t(d), 0.0f);
    channels.allocate(std::size_t(n_loads * n_nodes), std::size_t(n_loads) * n_grid);
  }
  for (int l = 0; l < n_loads; ++l) {
    const LoadCase& lc = cases[std::size_t(l)];
    const auto L = std::size_t(l);
    target[L] = lc.target;
    for (int k = 0; k < d; ++k) {
      p_n[L * std::size_t(d) + std::size_t(k)] = lc.center[std::size_t(k)];
      g[L * std::size_t(d) + std::size_t(k)] = lc.direction[std::size_t(k)];
    }
    drawn.add(lc);  // before anything that may fail: one row per load case
    solver::TargetResult r;
    std::string failure;
    try {
      {
        auto t = out.times.scope("setup");
        sp.set_load_case(cfg, shape, lc);
      }
      normaliser[L] = first_normaliser(*problem);
      nl->reset();
      r = nl->solve_for_target(lc.target);
      out.times.add("solve", r.seconds_first_solve);
      out.times.add("alpha_search", r.seconds_total - r.seconds_first_solve);
    } catch (const std::runtime_error& e) {  // PETSc's and the solver's failures: data
      failure = std::string("error: ") + e.what();
    }  // a std::logic_error is a bug: it ends the run (the shard is redone on resume)
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
    {
      auto t = out.times.scope("error_estimate");
      label_errors.estimate(group, cfg, shape, cases[0], lc, *problem, nl->solution(), r.alpha);
    }
    if (!root) continue;
    auto t = out.times.scope("representations");
    const std::size_t off = L * std::size_t(n_nodes * d);
    std::copy(u.values.begin(), u.values.end(), displacement.begin() + std::ptrdiff_t(off));
    moments.add("displacement", u.values.data(), u.values.size(), d);
    channels.fill(*problem, L, alpha[L], d, nodes, neumann_mask, grid, moments);
    if (cfg.representations.grid) {
      const std::size_t goff = L * n_grid * std::size_t(d);
      std::vector<double> gu(n_grid * std::size_t(d));
      sampler->interpolate(u.values, d, gu);
      std::copy(gu.begin(), gu.end(), grid_u.begin() + std::ptrdiff_t(goff));
      moments.add("grid_displacement", gu.data(), gu.size(), d);
    }
    moments.add("alpha", &alpha[L], 1, 1);
  }

  if (root) {
    auto t = out.times.scope("representations");
    const U64 nl_ = U64(n_loads), du = U64(d);
    const bool has_traction = n_tractions(cfg) > 0;
    arrays.push_back(schema_array("loads/status", {nl_}, status));
    arrays.push_back(schema_array("loads/alpha", {nl_}, alpha));
    arrays.push_back(schema_array("loads/target", {nl_}, target));
    arrays.push_back(schema_array("loads/max_displacement", {nl_}, max_u));
    arrays.push_back(schema_array("loads/min_det_f", {nl_}, min_det));
    if (has_traction)
      arrays.push_back(schema_array("loads/traction_normaliser", {nl_}, normaliser));
    arrays.push_back(schema_array("loads/newton_iterations", {nl_}, newton));
    arrays.push_back(schema_array("loads/solves", {nl_}, solves));
    arrays.push_back(schema_array("loads/failed_increments", {nl_}, failed_inc));
    arrays.push_back(schema_array("loads/recovery_iterations", {nl_}, recovery));
    if (has_traction) {
      arrays.push_back(schema_array("loads/p_n", {nl_, du}, p_n));
      arrays.push_back(schema_array("loads/g", {nl_, du}, g));
    }
    arrays.push_back(schema_array("loads/displacement", {nl_, U64(n_nodes), du}, std::move(displacement)));
    if (cfg.representations.grid) {
      std::vector<U64> s{nl_};
      s.insert(s.end(), grid_shape.begin(), grid_shape.end());
      s.push_back(du);
      arrays.push_back(schema_array("loads/grid_displacement", s, std::move(grid_u)));
    }
    label_errors.store(arrays);
    channels.store(arrays, nl_, U64(n_nodes), grid_shape);
    drawn.store(arrays);
    moments.store(arrays);
    out.entry.load_reasons = std::move(reasons);
  }
  return out;
}

}  // namespace hypershape::factory
