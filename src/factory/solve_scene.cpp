#include "hypershape/factory/solve_scene.hpp"

#include <fmt/format.h>
#include <petscsys.h>

#include <algorithm>
#include <optional>

#include "hypershape/core/collective.hpp"
#include "hypershape/core/error.hpp"
#include "hypershape/factory/shape_pipeline.hpp"
#include "hypershape/geometry/random_shape.hpp"
#include "hypershape/mesh/boundary_mesher.hpp"
#include "hypershape/mesh/gmsh_mesher.hpp"
#include "hypershape/physics/problem.hpp"
#include "hypershape/physics/scene.hpp"
#include "hypershape/solver/nonlinear.hpp"

namespace hypershape::factory {

namespace {

/// The clamp the mesher must conform to: the scene's dirichlet_patch, if any.
std::optional<mesh::ClampRegion> clamp_of(const std::vector<physics::ResolvedEffect>& effects, int dim) {
  for (const auto& e : effects)
    if (e.name == "dirichlet_patch") {
      mesh::ClampRegion c;
      auto v = e.params.vector("center", std::size_t(dim));
      std::copy(v.begin(), v.end(), c.center.begin());
      c.radius = e.params.number("radius");
      return c;
    }
  return std::nullopt;
}

/// The unit ball meshed as the factory meshes a 3D shape (the scene's surface_h / rim keys): a
/// level-6 icosphere (edges ~0.016) as the drawn surface, factory::solve_surface, mesh_boundary.
mesh::MeshData ball_as_a_shape(const config::Scene& scene, const std::optional<mesh::ClampRegion>& clamp) {
  ShapeConfig c;
  c.dim = 3;
  c.h = 0;  // the icosphere is only the geometry: always remeshed
  c.mesh_h = scene.h;
  c.surface_h = scene.surface_h;
  c.rim_size = scene.rim_size;
  c.dirichlet_radius = clamp ? clamp->radius : 0.0;
  const geometry::Boundary surface = solve_surface(geometry::icosphere(6), c, clamp ? clamp->center : std::array<double, 3>{});
  mesh::BoundaryMeshOptions mo;
  mo.h = scene.h;
  mo.grading = c.size_grading;
  return mesh::mesh_boundary(surface, mo);
}

/// Each target of `runs` (or the scene's target or alpha) solved in turn, `runs.repeat` times
/// over, each from rest on the same solver; the last one's outcome in `o`. Collective.
void solve_load_cases(const physics::Problem& problem, solver::NonlinearSolver& nl, config::Scene& scene,
                      const SceneRuns& runs, SceneOutcome& o) {
  std::vector<std::optional<double>> targets;
  for (double v : runs.targets) targets.emplace_back(v);
  if (targets.empty()) targets.push_back(scene.target);
  for (int rep = 0; rep < std::max(runs.repeat, 1); ++rep)
    for (const auto& target : targets) {
      if (!o.load_cases.empty()) nl.reset();
      const double t0 = core::now_seconds();
      if (target) {
        auto r = nl.solve_for_target(*target);
        o.converged = r.converged;
        o.reason = r.reason;
        o.alpha = r.alpha;
        o.newton_iterations = r.newton_iterations;
        o.solves = r.solves;
        o.failed_increments = r.failed_increments;
      } else {
        auto r = nl.solve(*scene.alpha);
        o.converged = r.converged;
        o.reason = r.reason;
        o.alpha = r.load_factor;
        o.newton_iterations = r.newton_iterations;
        o.solves = 1;
        o.failed_increments = r.failed_increments;
      }
      const double seconds = core::now_seconds() - t0;
      o.load_cases.push_back({target.value_or(0.0), o.alpha, problem.max_displacement(nl.solution()), seconds,
                              o.newton_iterations, o.converged});
    }
  if (targets.back()) scene.target = targets.back();
  o.max_displacement = problem.max_displacement(nl.solution());
  o.min_det_f = problem.min_det_f(nl.solution());
}

/// The solution file's record (rank 0): mesh, displacement, the scene, numbers, timings.
void fill_record(const physics::Space& sp, const config::Scene& scene, std::vector<double> displacement,
                 SceneOutcome& o) {
  auto& r = o.record;
  r.dim = o.dim;
  r.degree = o.degree;
  r.n_vertices = o.n_vertices;
  r.nodes = sp.canonical_coords();
  r.cells = sp.canonical_cells();
  r.displacement = std::move(displacement);
  r.scene_text = scene.text;
  r.numbers = {{"alpha", o.alpha},
               {"max_displacement", o.max_displacement},
               {"min_det_F", o.min_det_f},
               {"converged", o.converged ? 1.0 : 0.0},
               {"newton_iterations", double(o.newton_iterations)}};
  if (scene.target) r.numbers["target"] = *scene.target;
  r.strings = {{"reason", o.reason}, {"source", scene.source}};
  if (o.load_cases.size() > 1) {
    auto column = [&](const char* name, auto get) {
      auto& v = r.timings[name];
      for (const auto& c : o.load_cases) v.push_back(double(get(c)));
    };
    column("target", [](const auto& c) { return c.target; });
    column("alpha", [](const auto& c) { return c.alpha; });
    column("max_displacement", [](const auto& c) { return c.max_displacement; });
    column("converged", [](const auto& c) { return c.converged; });
    column("newton_iterations", [](const auto& c) { return c.newton_iterations; });
  }
  for (const auto& c : o.load_cases) r.timings["seconds"].push_back(c.seconds);
}

}  // namespace

SceneOutcome solve_scene(MPI_Comm comm, const config::Scene& scene_in, const SceneRuns& runs) {
  SceneOutcome o;
  config::Scene scene = scene_in;
  mesh::MeshData m;
  {
    auto t = o.times.scope("mesh");
    // For a mesh file the dimension comes from the file.
    if (scene.base == "file") {
      core::on_root(comm, [&] { m = mesh::read_mesh_file(scene.mesh_file); });
      int d = m.dim;
      MPI_Bcast(&d, 1, MPI_INT, 0, comm);
      scene.dim = d;
    }
  }
  // A scene file holds numbers only (config::parse_scene_text rejects distributions).
  const auto resolved = physics::resolve(scene.effects, [](std::size_t, const std::string&, const physics::Draw& d) {
    return d.low();
  });
  // Validate every effect before any mesh or solver work (build_problem builds them again).
  (void)physics::build_effects(scene.source, resolved, scene.dim, bool(scene.target));
  solver::set_default_options(scene.petsc);
  {
    auto t = o.times.scope("mesh");
    if (scene.base != "file") {
      mesh::MeshOptions mo;
      mo.h = scene.h;
      // 2D: mesh.rim (the datasets' key) is the size at the patch ends itself.
      mo.clamp_size = scene.dim == 2 && scene.rim_size > 0 ? scene.rim_size : scene.h * scene.clamp_refinement;
      auto clamp = clamp_of(resolved, scene.dim);
      core::on_root(comm, [&] {
        m = scene.base == "polygon"                         ? mesh::mesh_polygon(scene.polygon, scene.h)
            : scene.dim == 2                                ? mesh::mesh_disk(mo, clamp)
            : scene.surface_h > 0 || scene.rim_size > 0 ? ball_as_a_shape(scene, clamp)
                                                            : mesh::mesh_ball(mo, clamp);
      });
    }
  }
  std::unique_ptr<physics::Problem> problem;
  std::unique_ptr<solver::NonlinearSolver> nl;
  {
    auto t = o.times.scope("setup");
    try {
      problem = physics::build_problem(comm, m, scene.source, resolved, scene.dim,
                                       physics::SpaceOptions{scene.degree}, bool(scene.target));
    } catch (core::InputError& e) {
      throw core::InputError(scene.source, "", e.what());
    }
    nl = std::make_unique<solver::NonlinearSolver>(*problem, scene.solver);
  }
  {
    auto t = o.times.scope("solve");
    solve_load_cases(*problem, *nl, scene, runs, o);
  }
  const auto& sp = problem->space();
  o.dim = sp.dim();
  o.degree = sp.degree();
  o.n_vertices = sp.n_vertices_global();
  o.n_cells = sp.n_cells_global();
  o.n_dofs = sp.n_dofs_global();
  {
    auto t = o.times.scope("gather");
    auto field = problem->gather(nl->solution());
    if (core::rank(comm) == 0) fill_record(sp, scene, std::move(field.values), o);
  }
  return o;
}

std::string summary_line(const SceneOutcome& o) {
  std::string times;
  for (auto& [k, v] : o.times.all()) times += fmt::format(" {} {:.3f}s", k, v);
  if (o.load_cases.size() > 1) {
    times += " | load case s:";
    for (const auto& c : o.load_cases) times += fmt::format(" {:.4f}", c.seconds);
  }
  return fmt::format("{}D P{}: {} vertices, {} cells, {} dofs | {} | alpha {:.6g}, max|u| {:.6g}, min det F {:.3f} | "
                     "{} Newton iterations in {} solves ({} failed increments) |{}",
                     o.dim, o.degree, o.n_vertices, o.n_cells, o.n_dofs,
                     o.converged ? "converged" : "NOT converged: " + o.reason, o.alpha,
                     o.max_displacement, o.min_det_f, o.newton_iterations, o.solves,
                     o.failed_increments, times);
}

}  // namespace hypershape::factory
