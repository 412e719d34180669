#include "hypershape/factory/shape_job.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <numeric>
#include <optional>

#include "hypershape/core/error.hpp"
#include "hypershape/core/log.hpp"
#include "hypershape/factory/accuracy.hpp"
#include "hypershape/factory/dataset_schema.hpp"
#include "hypershape/factory/label_error.hpp"
#include "hypershape/factory/load_cases.hpp"
#include "hypershape/factory/p1_start.hpp"
#include "hypershape/factory/shape_pipeline.hpp"
#include "hypershape/factory/shape_set.hpp"
#include "hypershape/geometry/distance.hpp"
#include "hypershape/mesh/boundary_nodes.hpp"
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

/// The per-load-case rows of a shape ("loads/<name>", one row per load case), filled load case
/// by load case and stored at the end. A failed load case keeps zeros (never NaN).
struct LoadTable {
  LoadTable(int n_loads, int d)
      : d(d), status(std::size_t(n_loads), 0), reasons(std::size_t(n_loads)), alpha(std::size_t(n_loads), 0),
        target(std::size_t(n_loads)), max_u(std::size_t(n_loads), 0), min_det(std::size_t(n_loads), 0),
        normaliser(std::size_t(n_loads), 0), p_n(std::size_t(n_loads * d)), g(std::size_t(n_loads * d)),
        newton(std::size_t(n_loads), 0), solves(std::size_t(n_loads), 0), failed_inc(std::size_t(n_loads), 0),
        recovery(std::size_t(n_loads), 0) {}

  void set_case(std::size_t L, const LoadCase& lc) {
    target[L] = lc.target;
    for (int k = 0; k < d; ++k) {
      p_n[L * std::size_t(d) + std::size_t(k)] = lc.center[std::size_t(k)];
      g[L * std::size_t(d) + std::size_t(k)] = lc.direction[std::size_t(k)];
    }
  }
  void set_cost(std::size_t L, const solver::TargetResult& r) {
    newton[L] = r.newton_iterations;
    solves[L] = r.solves;
    failed_inc[L] = r.failed_increments;
    recovery[L] = r.recovery_iterations;
  }
  /// Load case L's row as `o` holds it.
  void take(std::size_t L, const LoadTable& o) {
    status[L] = o.status[L], reasons[L] = o.reasons[L], alpha[L] = o.alpha[L], target[L] = o.target[L];
    max_u[L] = o.max_u[L], min_det[L] = o.min_det[L], normaliser[L] = o.normaliser[L];
    for (std::size_t k = L * std::size_t(d); k < (L + 1) * std::size_t(d); ++k) p_n[k] = o.p_n[k], g[k] = o.g[k];
    newton[L] = o.newton[L], solves[L] = o.solves[L], failed_inc[L] = o.failed_inc[L], recovery[L] = o.recovery[L];
  }
  void store(std::vector<io::Array>& arrays, bool has_traction) const {
    const U64 n = U64(status.size()), du = U64(d);
    arrays.push_back(schema_array("loads/status", {n}, status));
    arrays.push_back(schema_array("loads/alpha", {n}, alpha));
    arrays.push_back(schema_array("loads/target", {n}, target));
    arrays.push_back(schema_array("loads/max_displacement", {n}, max_u));
    arrays.push_back(schema_array("loads/min_det_f", {n}, min_det));
    if (has_traction) arrays.push_back(schema_array("loads/traction_normaliser", {n}, normaliser));
    arrays.push_back(schema_array("loads/newton_iterations", {n}, newton));
    arrays.push_back(schema_array("loads/solves", {n}, solves));
    arrays.push_back(schema_array("loads/failed_increments", {n}, failed_inc));
    arrays.push_back(schema_array("loads/recovery_iterations", {n}, recovery));
    if (!has_traction) return;
    arrays.push_back(schema_array("loads/p_n", {n, du}, p_n));
    arrays.push_back(schema_array("loads/g", {n, du}, g));
  }

  int d;
  std::vector<std::int8_t> status;
  std::vector<std::string> reasons;
  std::vector<double> alpha, target, max_u, min_det, normaliser, p_n, g;
  std::vector<std::int64_t> newton, solves, failed_inc, recovery;
};

/// What a shape stores once (group root): the mesh, the boundary masks, the SDF and Dirichlet
/// distance at the nodes and on the grid, and the sampler that takes nodal fields to the grid.
struct ShapeFields {
  int d = 0;
  std::vector<double> nodes;
  std::vector<std::int64_t> cells;
  std::int64_t n_nodes = 0;
  std::vector<std::int8_t> dirichlet_mask, neumann_mask;
  std::vector<double> grid;  // grid points (empty without a grid)
  std::uint64_t n_grid = 0;
  std::vector<std::uint64_t> grid_shape;
  std::unique_ptr<sampling::MeshSampler> sampler;
};

void add_mesh(const config::DatasetConfig& cfg, const ShapeSample& shape, const physics::Space& space, ShapeFields& f,
              std::vector<io::Array>& arrays) {
  const int d = f.d;
  f.nodes = space.canonical_coords();
  f.cells = space.canonical_cells();
  f.n_nodes = std::int64_t(f.nodes.size()) / d;
  const auto per_cell = std::uint64_t(f.cells.size()) / std::uint64_t(shape.mesh.n_cells());
  arrays.push_back(schema_array("nodes", {U64(f.n_nodes), U64(d)}, f.nodes));
  arrays.push_back(schema_array("cells", {U64(shape.mesh.n_cells()), per_cell}, f.cells));
  mesh::boundary_node_masks(shape.boundary, shape.dirichlet_facets, f.cells, cfg.degree, f.n_nodes, f.dirichlet_mask,
                      f.neumann_mask);
  arrays.push_back(schema_array("dirichlet_mask", {U64(f.n_nodes)}, f.dirichlet_mask));
  arrays.push_back(schema_array("neumann_mask", {U64(f.n_nodes)}, f.neumann_mask));
}

void add_distances(const config::DatasetConfig& cfg, const ShapeSample& shape, ShapeFields& f, Moments& moments,
                   std::vector<io::Array>& arrays) {
  const geometry::SignedDistance sdf(shape.boundary);
  std::vector<std::int64_t> dfacets(shape.dirichlet_facets.begin(), shape.dirichlet_facets.end());
  const geometry::FacetSetDistance ddist(shape.boundary, dfacets);
  if (cfg.representations.point_cloud) {
    std::vector<double> s(static_cast<std::size_t>(f.n_nodes)), dd(static_cast<std::size_t>(f.n_nodes));
    sdf.evaluate(f.nodes, s);
    ddist.evaluate(f.nodes, dd);
    moments.add("sdf", s.data(), s.size(), 1);
    moments.add("dirichlet_distance", dd.data(), dd.size(), 1);
    arrays.push_back(schema_array("point_cloud/sdf", {U64(f.n_nodes)}, std::move(s)));
    arrays.push_back(schema_array("point_cloud/dirichlet_distance", {U64(f.n_nodes)}, std::move(dd)));
  }
  if (!cfg.representations.grid) return;
  const int N = cfg.representations.grid_size;
  f.grid = sampling::grid_points(f.d, N);
  f.n_grid = f.grid.size() / std::size_t(f.d);
  f.grid_shape.assign(std::size_t(f.d), U64(N));
  std::vector<double> s(f.n_grid), dd(f.n_grid);
  sdf.evaluate(f.grid, s);
  ddist.evaluate(f.grid, dd);
  moments.add("grid_sdf", s.data(), s.size(), 1);
  moments.add("grid_dirichlet_distance", dd.data(), dd.size(), 1);
  arrays.push_back(schema_array("grid/sdf", f.grid_shape, to_float(s)));
  arrays.push_back(schema_array("grid/dirichlet_distance", f.grid_shape, to_float(dd)));
  f.sampler = std::make_unique<sampling::MeshSampler>(f.d, cfg.degree, f.nodes, f.cells, shape.boundary, sdf, f.grid);
  const auto inside = f.sampler->inside();
  arrays.push_back(schema_array("grid/inside", f.grid_shape, std::vector<std::int8_t>(inside.begin(), inside.end())));
}

ShapeFields shape_fields(const config::DatasetConfig& cfg, const ShapeSample& shape, const physics::Space& space,
                         Moments& moments, std::vector<io::Array>& arrays) {
  ShapeFields f;
  f.d = cfg.shapes.dim;
  add_mesh(cfg, shape, space, f, arrays);
  add_distances(cfg, shape, f, moments, arrays);
  return f;
}

/// The fields every converged load case stores (group root): u at the nodes and on the grid,
/// and the scene's input channels.
class LoadFields {
 public:
  LoadFields(const physics::Problem& p, const config::DatasetConfig& cfg, const ShapeFields& f, int n_loads)
      : cfg_(cfg), f_(f), n_loads_(n_loads), channels_(p, cfg.representations) {}
  void allocate() {
    const int d = f_.d;
    displacement_.assign(std::size_t(n_loads_ * f_.n_nodes * d), 0.0);
    if (cfg_.representations.grid) grid_u_.assign(std::size_t(n_loads_) * f_.n_grid * std::size_t(d), 0.0f);
    channels_.allocate(std::size_t(n_loads_ * f_.n_nodes), std::size_t(n_loads_) * f_.n_grid);
  }
  void fill(const physics::Problem& p, std::size_t L, double alpha, const std::vector<double>& u, Moments& moments) {
    const int d = f_.d;
    std::copy(u.begin(), u.end(), displacement_.begin() + std::ptrdiff_t(L * std::size_t(f_.n_nodes * d)));
    moments.add("displacement", u.data(), u.size(), d);
    channels_.fill(p, L, alpha, d, f_.nodes, f_.neumann_mask, f_.grid, moments);
    if (cfg_.representations.grid) {
      std::vector<double> gu(f_.n_grid * std::size_t(d));
      f_.sampler->interpolate(u, d, gu);
      std::copy(gu.begin(), gu.end(), grid_u_.begin() + std::ptrdiff_t(L * f_.n_grid * std::size_t(d)));
      moments.add("grid_displacement", gu.data(), gu.size(), d);
    }
  }
  void store(std::vector<io::Array>& arrays) {
    const U64 n = U64(n_loads_), du = U64(f_.d);
    arrays.push_back(schema_array("loads/displacement", {n, U64(f_.n_nodes), du}, std::move(displacement_)));
    if (cfg_.representations.grid) {
      std::vector<U64> s{n};
      s.insert(s.end(), f_.grid_shape.begin(), f_.grid_shape.end());
      s.push_back(du);
      arrays.push_back(schema_array("loads/grid_displacement", s, std::move(grid_u_)));
    }
    channels_.store(arrays, n, U64(f_.n_nodes), f_.grid_shape);
  }

 private:
  const config::DatasetConfig& cfg_;
  const ShapeFields& f_;
  int n_loads_;
  Channels channels_;
  std::vector<double> displacement_;
  std::vector<float> grid_u_;
};

/// A shape with no acceptable draw: a failed entry, every load case failed.
void record_failed_shape(const config::DatasetConfig& cfg, std::int64_t shape_id, const std::string& why,
                         ShapeJobResult& out) {
  out.entry.ok = false;
  out.entry.failure = why;
  out.entry.shape.shape_id = shape_id;
  out.entry.shape.dim = cfg.shapes.dim;
  out.entry.shape.rejected = why;
  out.entry.shape.numbers = {{"failed", 1}};
  out.entry.shape.source_file = source_file(cfg.shapes, shape_id);
  out.counters.loads_failed = cfg.loads.count;
}

/// The shape of `shape_id` (every rank of the group draws the same one), or nothing when no
/// draw is acceptable (then `out` holds the failed entry).
std::optional<ShapeSample> draw_shape(const config::DatasetConfig& cfg, const std::optional<geometry::Boundary>& base,
                                      std::int64_t shape_id, ShapeJobResult& out) {
  ShapeSample shape;
  {
    auto t = out.times.scope("shape");
    try {
      shape = make_shape(shape_config(cfg, shape_id), base, cfg.seed, shape_id);
    } catch (const std::runtime_error& e) {
      record_failed_shape(cfg, shape_id, e.what(), out);
      return std::nullopt;
    }
  }
  out.times.add("mesh", shape.seconds_mesh);
  out.times.add("shape", -shape.seconds_mesh);
  out.entry.shape = to_record(shape);
  for (auto it = out.entry.shape.numbers.begin(); it != out.entry.shape.numbers.end();)
    it = it->first.rfind("seconds_", 0) == 0 ? out.entry.shape.numbers.erase(it) : std::next(it);
  return shape;
}

/// One load case solved and checked: its outcome (converged, finite, no inverted cell) and,
/// when it converged, the displacement at the nodes (on the group root).
struct LoadOutcome {
  bool ok = false;
  std::string reason;
  solver::TargetResult result;
  double max_u = 0, min_det = 0;
  physics::NodalField u;
};

/// A start for a load case's solve other than rest: the state the error estimate of its label on a
/// coarser level reached on this level's mesh, at that label's alpha.
struct WarmStart {
  core::VecH u;
  double alpha = 0;
  int level = 0;  ///< the coarser level
};

/// The load case's target solve: from rest or, given `warm`, from there (and from rest where that
/// fails; the failed try counted as discarded work).
solver::TargetResult solve_target(solver::NonlinearSolver& nl, const LoadCase& lc, const WarmStart* warm) {
  nl.reset();
  if (!warm) return nl.solve_for_target(lc.target);
  solver::TargetResult t = nl.solve_for_target_from(warm->u, warm->alpha, lc.target);
  if (t.converged) {
    t.reason = fmt::format("from the level-{} estimate: {}", warm->level, t.reason);
    return t;
  }
  const solver::TargetResult first = t;
  nl.reset();
  t = nl.solve_for_target(lc.target);
  t.add_discarded_solve(first);
  t.reason = fmt::format("{} (from rest; from the level-{} estimate: {})", t.reason, warm->level, first.reason.substr(0, 300));
  return t;
}

LoadOutcome solve_load_case(MPI_Comm group, const config::DatasetConfig& cfg, const ShapeSample& shape,
                            ShapeProblem& sp, solver::NonlinearSolver& nl, P1Start& p1, const LoadCase& lc,
                            const WarmStart* warm, core::PhaseTimes& times, double& normaliser) {
  LoadOutcome o;
  std::string failure;
  try {
    {
      auto t = times.scope("setup");
      sp.set_load_case(cfg, shape, lc);
    }
    normaliser = first_normaliser(*sp.problem);
    o.result = solve_target(nl, lc, warm);
    times.add("solve", o.result.seconds_first_solve);
    times.add("alpha_search", o.result.seconds_total - o.result.seconds_first_solve);
    if (p1.applies(o.result)) {
      auto t = times.scope("alpha_search");
      std::string note;
      try {  // the rescue's own failure leaves the load case's failure and its reason standing
        if (auto r = p1.solve(lc, nl, o.result, note)) o.result = std::move(*r);
      } catch (const std::runtime_error& e) {
        note = std::string("; P1 start: error: ") + e.what();
      }
      if (!note.empty()) o.result.reason += note;
    }
  } catch (const std::runtime_error& e) {  // PETSc's and the solver's failures: data
    failure = std::string("error: ") + e.what();
  }  // a std::logic_error is a bug: it ends the run (the shard is redone on resume)
  o.ok = failure.empty() && o.result.converged;
  {
    auto t = times.scope("gather");
    const physics::Problem& problem = *sp.problem;
    o.max_u = problem.max_displacement(nl.solution());
    o.min_det = problem.min_det_f(nl.solution());
    o.u = problem.gather(nl.solution());
    if (o.ok && !(std::isfinite(o.max_u) && std::isfinite(o.min_det))) o.ok = false, failure = "non-finite displacement";
    if (o.ok && !(o.min_det > 0)) o.ok = false, failure = "inverted cells (min det F <= 0)";
  }
  if (core::rank(group) == 0 && o.ok && !all_finite(o.u.values)) o.ok = false, failure = "non-finite displacement";
  MPI_Bcast(&o.ok, 1, MPI_CXX_BOOL, 0, group);
  o.reason = o.ok ? o.result.reason : (failure.empty() ? o.result.reason : failure);
  return o;
}

/// One discretisation of a shape (the config's own; in a dataset asked for by accuracy, a rung of
/// its ladder) and what the load cases solved on it gave: their rows, estimates and cost and
/// (group root) the converged ones' displacements. The problem is kept after the solves: a label's
/// stored input channels are those of the problem it was solved on (its traction normaliser).
struct Level {
  Level(MPI_Comm group, const config::DatasetConfig& c, ShapeSample s, const LoadCase& first, core::PhaseTimes& times)
      : cfg(c), shape(std::move(s)), table(c.loads.count, c.shapes.dim), errors(c, c.loads.count),
        u(std::size_t(c.loads.count)), factorizations(std::size_t(c.loads.count), 0),
        solved(std::size_t(c.loads.count), 0) {
    auto t = times.scope("setup");
    sp = make_shape_problem(group, cfg, shape, first);
  }
  config::DatasetConfig cfg;
  ShapeSample shape;
  ShapeProblem sp;
  LoadTable table;
  LabelErrors errors;
  std::vector<std::vector<double>> u;          ///< group root: the converged labels' nodal displacement (moved out by store_shape)
  std::vector<std::int64_t> factorizations;    ///< numeric factorisations of each load case solved here
  std::vector<char> solved;                    ///< 1: the load case was solved here
};

/// A load case's start other than rest, if any (WarmStart); collective.
using WarmStarts = std::function<std::optional<WarmStart>(int load)>;

/// Solves the load cases `which` of `lv` (the solver set up once for them all; each from rest or
/// from `warm`'s start, if given) and records them in `lv`; their solver work goes to
/// out.counters, `on_load(converged)` runs after each. Collective.
void solve_loads(MPI_Comm group, Level& lv, const std::vector<LoadCase>& cases, const std::vector<int>& which,
                 const WarmStarts& warm, const std::function<void(bool)>& on_load, ShapeJobResult& out) {
  std::unique_ptr<solver::NonlinearSolver> nl;
  {
    auto t = out.times.scope("setup");
    nl = std::make_unique<solver::NonlinearSolver>(*lv.sp.problem, lv.cfg.solver);
  }
  P1Start p1(group, lv.cfg, lv.shape);  // built at the first load case it rescues
  for (int l : which) {
    const auto L = std::size_t(l);
    lv.table.set_case(L, cases[L]);
    lv.solved[L] = 1;
    const std::optional<WarmStart> start = warm ? warm(l) : std::nullopt;
    LoadOutcome o = solve_load_case(group, lv.cfg, lv.shape, lv.sp, *nl, p1, cases[L], start ? &*start : nullptr,
                                    out.times, lv.table.normaliser[L]);
    lv.table.set_cost(L, o.result);
    lv.factorizations[L] = o.result.linear.numeric_factorizations;
    out.counters.add(o.result);
    lv.table.status[L] = o.ok ? 1 : 0;
    lv.table.reasons[L] = o.reason;
    if (on_load) on_load(o.ok);
    if (!o.ok) continue;  // a failed load case: the row and the fields stay zero, never NaN
    lv.table.max_u[L] = o.max_u, lv.table.min_det[L] = o.min_det, lv.table.alpha[L] = o.result.alpha;
    {
      auto t = out.times.scope("error_estimate");
      // The coarse level: the factor the solve left (no second coarse factorisation).
      lv.errors.estimate(group, lv.cfg, lv.shape, cases[0], cases[L], *lv.sp.problem, nl->solution(), o.result.alpha,
                         [&](Vec x, Vec y, bool refined) { return nl->apply_tangent_factor(x, y, refined); });
    }
    lv.u[L] = std::move(o.u.values);
  }
  lv.errors.release_estimator();
}

/// The largest nodal |u| of a displacement field of `d` components.
double max_norm(const std::vector<double>& u, int d) {
  double m = 0;
  for (std::size_t i = 0; i + std::size_t(d) <= u.size(); i += std::size_t(d)) {
    double s = 0;
    for (int k = 0; k < d; ++k) s += u[i + std::size_t(k)] * u[i + std::size_t(k)];
    m = std::max(m, s);
  }
  return std::sqrt(m);
}

/// Stores the shape on level `levels[stored]` (its mesh and representations), load case L's
/// label taken from levels[from[L]] (a coarser level's displacement carried to the stored mesh
/// exactly: the levels are nested, P1 in P2 on one mesh, P2 in P2 on the mesh refined; its
/// max_displacement then counts the stored nodes). Collective over `group` (the load cases'
/// input channels are evaluated with the problem each label was solved on).
void store_shape(MPI_Comm group, const std::vector<std::unique_ptr<Level>>& levels, int stored,
                 const std::vector<int>& from, const std::vector<LoadCase>& cases, ShapeJobResult& out) {
  const bool root = core::rank(group) == 0;
  const Level& top = *levels[std::size_t(stored)];
  const config::DatasetConfig& cfg = top.cfg;
  const int n_loads = cfg.loads.count, d = cfg.shapes.dim;
  out.n_dofs = top.sp.problem->space().n_dofs_global();
  auto& arrays = out.entry.arrays;
  Moments moments;
  ShapeFields fields;
  if (root) {
    auto t = out.times.scope("representations");
    fields = shape_fields(cfg, top.shape, top.sp.problem->space(), moments, arrays);
  }
  LoadTable table(n_loads, d);
  LoadFields load_fields(*top.sp.problem, cfg, fields, n_loads);
  DrawnParams drawn(cfg, top.shape.shape_id, n_loads);
  LabelErrors errors(cfg, n_loads);
  std::map<int, sampling::MeshSampler> to_stored;  // root: a coarser level's fields at the stored nodes
  if (root) load_fields.allocate();
  for (int l = 0; l < n_loads; ++l) {
    const auto L = std::size_t(l);
    Level& lv = *levels[std::size_t(from[L])];
    table.take(L, lv.table);
    errors.take(L, lv.errors);
    drawn.add(cases[L]);
    (table.status[L] ? out.counters.loads_ok : out.counters.loads_failed) += 1;
    if (!table.status[L]) continue;
    lv.sp.set_load_case(lv.cfg, lv.shape, cases[L]);  // collective: the channels of the label's own problem
    if (!root) continue;
    auto t = out.times.scope("representations");
    std::vector<double> u = std::move(lv.u[L]);  // its last use: no second copy of every label
    if (from[L] != stored) {
      auto it = to_stored.find(from[L]);
      if (it == to_stored.end()) {
        const physics::Space& s = lv.sp.problem->space();
        it = to_stored.try_emplace(from[L], d, s.degree(), s.canonical_coords(), s.canonical_cells(), lv.shape.boundary,
                                   fields.nodes).first;
      }
      u = it->second.interpolate(u, d);
      table.max_u[L] = max_norm(u, d);
    }
    load_fields.fill(*lv.sp.problem, L, table.alpha[L], u, moments);
    moments.add("alpha", &table.alpha[L], 1, 1);
  }
  if (!root) return;
  auto t = out.times.scope("representations");
  table.store(arrays, n_tractions(cfg) > 0);
  load_fields.store(arrays);
  errors.store(arrays);
  out.label_error = errors.summary(table.status);
  drawn.store(arrays);
  moments.store(arrays);
  out.entry.load_reasons = table.reasons;
}

/// The record of a shape as solved (its mesh), without the timings that would make it differ
/// from one run to the next.
io::ShapeRecord solved_record(const ShapeSample& shape) {
  io::ShapeRecord r = to_record(shape);
  for (auto it = r.numbers.begin(); it != r.numbers.end();)
    it = it->first.rfind("seconds_", 0) == 0 ? r.numbers.erase(it) : std::next(it);
  return r;
}

/// What the ladder did on one shape: out.accuracy (the stored level, each label's level, the
/// labels meeting the bound, the load cases solved again and the labels not kept, with their
/// cost), the shape's accuracy_* attributes and (`root`: the group root) loads/accuracy_level and
/// loads/accuracy_tried.
void summarise_accuracy(const config::DatasetConfig& cfg, const std::vector<std::unique_ptr<Level>>& levels,
                        int stored, const std::vector<int>& from, const std::vector<int>& tried, bool root,
                        ShapeJobResult& out) {
  AccuracySummary& s = out.accuracy;
  s.shapes_at_level[std::size_t(stored)] += 1;
  double worst = -1;
  std::int64_t converged = 0, exceeding = 0, discarded = 0;
  for (std::size_t L = 0; L < from.size(); ++L) {
    const Level& kept = *levels[std::size_t(from[L])];
    if (kept.table.status[L]) {
      const double e = kept.errors.rel_l2()[L];
      s.loads_at_level[std::size_t(from[L])] += 1;
      converged += 1;
      worst = std::max(worst, e);
      exceeding += exceeds(cfg.accuracy, e);
    }
    s.solved_again += tried[L] > 0;
    for (std::size_t k = 0; k < levels.size(); ++k) {
      if (!levels[k] || !levels[k]->solved[L] || int(k) == from[L]) continue;
      discarded += 1;
      s.discarded_newton += levels[k]->table.newton[L];
      s.discarded_factorizations += levels[k]->factorizations[L];
    }
  }
  s.discarded_loads += discarded;
  s.loads_exceeding += exceeding;
  s.loads_meeting += converged - exceeding;
  const AccuracyLevel a = accuracy_level(cfg, stored);
  auto& numbers = out.entry.shape.numbers;
  numbers["accuracy_level"] = stored;
  numbers["accuracy_degree"] = a.degree;
  numbers["accuracy_h"] = a.h;
  numbers["accuracy_estimate_max"] = worst;
  numbers["accuracy_exceeding"] = double(exceeding);
  numbers["accuracy_discarded_load_cases"] = double(discarded);
  if (!root) return;
  const auto n = std::uint64_t(from.size());
  out.entry.arrays.push_back(schema_array("loads/accuracy_level", {n}, std::vector<std::int8_t>(from.begin(), from.end())));
  out.entry.arrays.push_back(schema_array("loads/accuracy_tried", {n}, std::vector<std::int8_t>(tried.begin(), tried.end())));
}

/// The starts of level k's re-solves (`accuracy: {start: coarse}`): where the load case was solved
/// on level k - 1 (its label kept or not) and level k is that mesh refined once (the same degree),
/// the state that label's error estimate reached on level k's mesh (P u_h + e: the fine Newton's
/// state at the label's alpha, which has already relaxed what P u_h over-stretches next to the
/// clamp's ends), at that alpha. Not otherwise: measured on Random2D (2026-12-02), the label itself
/// carried to a finer mesh is no equilibrium there (its first increments creep, 37-149 Newton iterations against 26-110 from
/// rest), and a P1 label carried to P2 on its own mesh is a locked state far from P2's (3x the
/// factorisations of the re-solves from rest on the P1 test config). Group root; the node
/// permutation from level k - 1's refined mesh built at its first use.
WarmStarts estimates_reached(MPI_Comm group, const config::DatasetConfig& cfg,
                             const std::vector<std::unique_ptr<Level>>& levels, int k) {
  auto permutation = std::make_shared<std::optional<std::vector<std::int64_t>>>();
  return [group, &cfg, &levels, k, permutation](int l) -> std::optional<WarmStart> {
    const auto L = std::size_t(l);
    const int had = k - 1, d = cfg.shapes.dim;  // the level below, if this load case was solved there (kept or not)
    if (had < 0 || !levels[std::size_t(had)] || !levels[std::size_t(had)]->solved[L]) return std::nullopt;
    const Level& from = *levels[std::size_t(had)];
    const Level& to = *levels[std::size_t(k)];
    const AccuracyLevel a = accuracy_level(cfg, had), b = accuracy_level(cfg, k);
    if (!from.table.status[L] || from.errors.rel_l2()[L] < 0 || a.degree != b.degree ||
        b.refinements != a.refinements + 1)
      return std::nullopt;
    std::vector<double> u;
    bool found = true;
    if (core::rank(group) == 0) {
      if (!*permutation) {
        *permutation = node_permutation(from.errors.fine_coords(), to.sp.problem->space().canonical_coords(), d);
        if ((*permutation)->empty())  // not expected: both are the same mesh refined once
          core::info(group, "shape {}: the estimate's refined nodes differ from level {}'s: its re-solves start from rest",
                     from.shape.shape_id, k);
      }
      const auto& p = **permutation;
      const std::vector<double>& fine = from.errors.fine_state(L);
      found = !p.empty() && fine.size() == p.size() * std::size_t(d);
      if (found) {
        u.resize(fine.size());
        for (std::size_t j = 0; j < p.size(); ++j)
          for (int c = 0; c < d; ++c) u[j * std::size_t(d) + std::size_t(c)] = fine[std::size_t(p[j]) * std::size_t(d) + std::size_t(c)];
      }
    }
    MPI_Bcast(&found, 1, MPI_CXX_BOOL, 0, group);
    if (!found) return std::nullopt;
    return WarmStart{to.sp.problem->scatter(std::move(u)), from.table.alpha[L], had};
  };
}

/// The accuracy ladder (factory/accuracy.hpp), load case by load case, on one drawn shape: the
/// levels LoadLadder schedules, each set up once, when first needed, on the shape refined as often
/// as it asks. The shape is stored on the finest level a label was kept at, the coarser labels
/// carried to it exactly (store_shape).
void solve_by_accuracy(MPI_Comm group, const config::DatasetConfig& cfg, const ShapeSample& drawn,
                       const std::vector<LoadCase>& cases, const std::function<void(bool)>& on_load,
                       ShapeJobResult& out) {
  const int n = cfg.loads.count;
  std::vector<std::unique_ptr<Level>> levels(std::size_t(cfg.accuracy.max_level + 1));
  std::vector<ShapeSample> refined{drawn};  // [r]: the drawn shape refined r times
  auto level = [&](int k) -> Level& {
    auto& lv = levels[std::size_t(k)];
    if (lv) return *lv;
    const AccuracyLevel a = accuracy_level(cfg, k);
    while (int(refined.size()) <= a.refinements) refined.push_back(refine_shape(refined.back()));
    config::DatasetConfig at = cfg;
    at.degree = a.degree;
    if (k > 0 && cfg.accuracy.resolve_newton_budget > 0) at.solver.newton_budget = cfg.accuracy.resolve_newton_budget;
    if (k > 0 && !cfg.accuracy.resolve_retries) at.solver.retry_from_rest = at.solver.p1_start = false;
    lv = std::make_unique<Level>(group, at, refined[std::size_t(a.refinements)], cases[0], out.times);
    if (cfg.accuracy.start_from_coarse && k < cfg.accuracy.max_level && accuracy_level(cfg, k + 1).degree == a.degree)
      lv->errors.keep_fine_states();  // the next level's starts (estimates_reached)
    return *lv;
  };
  LoadLadder ladder(cfg, n);
  std::vector<int> todo(static_cast<std::size_t>(n));
  std::iota(todo.begin(), todo.end(), 0);
  for (int k = 0; k >= 0; k = ladder.next(todo)) {
    Level& lv = level(k);
    for (int l : todo) out.accuracy.fell_back += ladder.falls_back(l);
    solve_loads(group, lv, cases, todo, k > 0 && cfg.accuracy.start_from_coarse ? estimates_reached(group, cfg, levels, k) : WarmStarts{},
                k == 0 ? on_load : std::function<void(bool)>{}, out);
    for (int l : todo) {
      const auto L = std::size_t(l);
      const int had = ladder.kept(l);
      const double before = levels[std::size_t(had)]->errors.rel_l2()[L], e = lv.errors.rel_l2()[L];
      if (ladder.record(l, k, lv.table.status[L] != 0, e)) continue;
      core::info(group,
                 "shape {} load {}: keeps its level-{} label (estimate {:.3g}): at level {} it {} "
                 "({} Newton iterations, {} factorisations){}",
                 drawn.shape_id, L, had, before, k,
                 !lv.table.status[L] ? "failed (" + lv.table.reasons[L] + ")"
                 : e < 0             ? fmt::format("had no estimate ({:g})", e)
                                     : fmt::format("estimated {:.3g}", e),
                 lv.table.newton[L], lv.factorizations[L],
                 ladder.waiting(l) < 0     ? std::string()
                 : ladder.falls_back(l)    ? fmt::format("; it tries level {}, which it skipped", ladder.waiting(l))
                                           : fmt::format("; it climbs on to level {}", ladder.waiting(l)));
    }
  }
  const std::vector<int>& from = ladder.kept_levels();
  std::vector<int> tried(static_cast<std::size_t>(n));
  for (int L = 0; L < n; ++L) tried[std::size_t(L)] = ladder.highest_tried(L);
  const int stored = *std::max_element(from.begin(), from.end());
  out.entry.shape = solved_record(levels[std::size_t(stored)]->shape);
  store_shape(group, levels, stored, from, cases, out);
  summarise_accuracy(cfg, levels, stored, from, tried, core::rank(group) == 0, out);
}

}  // namespace

ShapeJobResult run_shape(MPI_Comm group, const config::DatasetConfig& cfg,
                         const std::optional<geometry::Boundary>& base, std::int64_t shape_id,
                         const std::function<void(bool)>& on_load) {
  ShapeJobResult out;
  const std::optional<ShapeSample> shape = draw_shape(cfg, base, shape_id, out);
  if (!shape) return out;
  const auto cases = draw_load_cases(*shape, cfg.loads, cfg.seed, n_tractions(cfg));
  if (cfg.accuracy.enabled()) {
    solve_by_accuracy(group, cfg, *shape, cases, on_load, out);
    return out;
  }
  std::vector<std::unique_ptr<Level>> levels;
  levels.push_back(std::make_unique<Level>(group, cfg, *shape, cases[0], out.times));
  std::vector<int> all(std::size_t(cfg.loads.count)), from(all.size(), 0);
  std::iota(all.begin(), all.end(), 0);
  solve_loads(group, *levels[0], cases, all, {}, on_load, out);
  store_shape(group, levels, 0, from, cases, out);
  return out;
}

}  // namespace hypershape::factory
