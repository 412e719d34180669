// 3D labels against a converged reference (issue 16 part B; see labels3d.hpp).
#include "hypershape/study/labels3d.hpp"

#include <petscsys.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "hypershape/config/dataset.hpp"
#include "hypershape/core/error.hpp"
#include "hypershape/core/timer.hpp"
#include "hypershape/factory/dataset_scene.hpp"
#include "hypershape/factory/load_cases.hpp"
#include "hypershape/geometry/random_shape.hpp"
#include "hypershape/geometry/surface_remesh.hpp"
#include "hypershape/io/solution_file.hpp"
#include "hypershape/mesh/boundary_mesher.hpp"
#include "hypershape/sampling/mesh_sampler.hpp"
#include "hypershape/solver/nonlinear.hpp"

namespace hypershape::study::labels3d {

using json = nlohmann::json;

Discretisation parse_discretisation(const std::string& spec) {
  Discretisation d;
  const auto colon = spec.find(':');
  d.name = spec.substr(0, colon);
  if (d.name.empty()) throw std::invalid_argument("discretisation '" + spec + "': no name before ':'");
  if (colon == std::string::npos) return d;
  std::stringstream ss(spec.substr(colon + 1));
  for (std::string item; std::getline(ss, item, ',');) {
    const auto eq = item.find('=');
    const std::string key = item.substr(0, eq), value = eq == std::string::npos ? "" : item.substr(eq + 1);
    auto number = [&] {
      try {
        const double v = std::stod(value);
        if (!(v >= 0) || !std::isfinite(v)) throw std::invalid_argument("");
        return v;
      } catch (const std::exception&) {
        throw std::invalid_argument("discretisation '" + spec + "': " + key + " must be a number >= 0");
      }
    };
    if (key == "h") d.surface_h = d.interior_h = number();
    else if (key == "surface_h") d.surface_h = number();
    else if (key == "interior_h") d.interior_h = number();
    else if (key == "rim") d.rim_size = number();
    else if (key == "load") d.load_size = number();
    else if (key == "grading") d.grading = number();
    else if (key == "label_on") d.label_on = value;
    else if (key == "dilatation") {
      if (value != "pointwise" && value != "mean")
        throw std::invalid_argument("discretisation '" + spec + "': dilatation must be pointwise or mean, not '" +
                                    value + "'");
      d.dilatation = value;
    } else if (key == "share") {
      d.pointwise_share = number();
    } else
      throw std::invalid_argument("discretisation '" + spec + "': unknown key '" + key +
                                  "' (allowed: h, surface_h, interior_h, rim, load, grading, label_on, dilatation=pointwise|mean, share)");
  }
  if (!(d.surface_h > 0 && d.interior_h > 0 && d.grading > 0))
    throw std::invalid_argument("discretisation '" + spec + "': h, surface_h, interior_h, grading must be > 0");
  return d;
}

namespace {

/// The scene: the preset's problem on one surface with one load case.
struct Scene {
  config::DatasetConfig cfg;
  geometry::Boundary surface;  ///< the shape as drawn (ball: a level-6 icosphere)
  std::array<double, 3> p_d{};
  double r = 0;
  factory::LoadCase lc;
};

double norm3(const std::array<double, 3>& a, const std::array<double, 3>& b);

/// Scene "r3d:SEED:SHAPE:LOAD": a load case of the random3d preset's factory at another seed; the
/// shape and the load case as the factory draws them (p_N on the preset's remeshed surface),
/// solved on the shape as drawn.
Scene factory_load_case(Scene s, const std::string& name) {
  unsigned long long seed = 0;
  int shape_id = -1, load_id = -1;
  if (std::sscanf(name.c_str(), "r3d:%llu:%d:%d", &seed, &shape_id, &load_id) != 3 || shape_id < 0 || load_id < 0 ||
      load_id >= s.cfg.loads.count)
    throw std::invalid_argument("scene '" + name + "' (allowed: ball, r3d-0, r3d:SEED:SHAPE:LOAD)");
  s.cfg.seed = seed;
  const factory::ShapeSample as_solved = factory::make_shape(factory::shape_config(s.cfg, shape_id), std::nullopt, seed, shape_id);
  factory::ShapeConfig c = factory::shape_config(s.cfg, shape_id);
  c.mesh_h = c.h, c.surface_h = 0, c.rim_size = 0;
  const factory::ShapeSample drawn = factory::make_shape(c, std::nullopt, seed, shape_id);
  if (norm3(drawn.dirichlet_center, as_solved.dirichlet_center) > 1e-12)
    throw std::invalid_argument("scene '" + name + "': the preset's remeshing redrew this shape (another draw)");
  s.surface = drawn.boundary;
  s.p_d = drawn.dirichlet_center;
  s.lc = factory::draw_load_cases(as_solved, s.cfg.loads, seed, factory::n_tractions(s.cfg)).at(std::size_t(load_id));
  return s;
}

Scene make_scene(const std::string& name) {
  Scene s;
  s.cfg = config::parse_dataset_text("preset: random3d\n", "<study_labels3d>");
  s.r = s.cfg.shapes.dirichlet_radius;
  if (name == "ball") {
    s.surface = geometry::icosphere(6);
    s.p_d = {1, 0, 0};
    s.lc.center = {-1, 0, 0};
    s.lc.direction = {0, 1, 0};
    return s;
  }
  if (name == "r3d-0") {
    factory::ShapeConfig c = factory::shape_config(s.cfg, 0);
    c.mesh_h = c.h;  // the surface as drawn
    c.surface_h = 0, c.rim_size = 0;  // no remeshing: the preset's own (rim) would redraw shape 0
    const factory::ShapeSample shape = factory::make_shape(c, std::nullopt, s.cfg.seed, 0);
    s.surface = shape.boundary;
    s.p_d = shape.dirichlet_center;
    s.lc = factory::draw_load_cases(shape, s.cfg.loads, s.cfg.seed, factory::n_tractions(s.cfg)).at(0);
    return s;
  }
  return factory_load_case(std::move(s), name);
}

double norm3(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

/// The discretisation's shape: surface remeshed (and refined), volume meshed.
factory::ShapeSample build_shape(const Scene& s, const Discretisation& d) {
  geometry::RemeshOptions ro;
  ro.target_edge = d.surface_h;
  ro.clamp_center = s.p_d;
  ro.clamp_radius = s.r;
  if (d.rim_size > 0 || d.load_size > 0) {
    ro.size = [&s, &d](const std::array<double, 3>& x) {
      double size = std::numeric_limits<double>::infinity();
      if (d.rim_size > 0) size = std::min(size, d.rim_size + d.grading * std::abs(norm3(x, s.p_d) - s.r));
      if (d.load_size > 0) size = std::min(size, d.load_size + d.grading * norm3(x, s.lc.center));
      return size;
    };
    const double finest = std::min(d.rim_size > 0 ? d.rim_size : 1e300, d.load_size > 0 ? d.load_size : 1e300);
    ro.min_edge = 0.5 * finest;
  }
  factory::ShapeSample out;
  out.boundary = geometry::remesh_surface(s.surface, ro);
  mesh::BoundaryMeshOptions mo;
  mo.h = d.interior_h;
  mo.grading = d.grading;
  out.mesh = mesh::mesh_boundary(out.boundary, mo);
  out.dirichlet_center = s.p_d;
  out.dirichlet_radius = s.r;
  out.dirichlet_facets = geometry::facets_in_ball(out.boundary, s.p_d, s.r);
  return out;
}

/// One discretisation solved at alpha: its mesh and P2 solution (canonical order) and costs.
struct Solved {
  factory::ShapeSample shape;
  std::vector<double> nodes, u;
  std::vector<std::int64_t> cells;
  std::int64_t dofs = 0, n_vertices = 0;
  double max_u = 0, min_det_f = 0;
  bool converged = false;
  std::string reason;
  int newton = 0, target_newton = 0, target_solves = 0;
  double t_mesh = 0, t_setup = 0, t_solve = 0, t_target = NAN;
};

const char* kPrefix = "l3d_";

/// MUMPS LDL^T: the references reach 10^5 unknowns (PETSc's own Cholesky is far slower there).
void set_linear_solver(bool set) {
  for (const auto& [k, v] : {std::pair{"pc_type", "cholesky"}, std::pair{"pc_factor_mat_solver_type", "mumps"}}) {
    const std::string name = std::string("-") + kPrefix + k;
    if (set)
      HS_PETSC(PetscOptionsSetValue(nullptr, name.c_str(), v));
    else
      HS_PETSC(PetscOptionsClearValue(nullptr, name.c_str()));
  }
}

Solved solve(const Scene& s, const Discretisation& d, double alpha, std::optional<double> target) {
  Solved o;
  double t0 = core::now_seconds();
  o.shape = build_shape(s, d);
  o.t_mesh = core::now_seconds() - t0;
  t0 = core::now_seconds();
  physics::SpaceOptions so;
  so.degree = 2;
  config::DatasetConfig cfg = s.cfg;
  for (auto i : cfg.scene.find("neo_hookean")) {
    cfg.scene.effects[i].params["dilatation"] = std::string(d.dilatation);
    if (d.pointwise_share > 0) cfg.scene.effects[i].params["pointwise_share"] = d.pointwise_share;
  }
  auto sp = factory::make_shape_problem(PETSC_COMM_SELF, cfg, o.shape, s.lc, so);
  const physics::Problem& problem = *sp.problem;
  set_linear_solver(true);
  solver::NonlinearSolver nl(problem, s.cfg.solver, kPrefix);
  o.t_setup = core::now_seconds() - t0;
  t0 = core::now_seconds();
  const auto r = nl.solve(alpha);
  o.t_solve = core::now_seconds() - t0;
  o.converged = r.converged;
  o.reason = r.reason;
  o.newton = r.newton_iterations;
  o.max_u = problem.max_displacement(nl.solution());
  o.min_det_f = problem.min_det_f(nl.solution());
  o.u = problem.gather(nl.solution()).values;
  const auto& space = problem.space();
  o.dofs = space.n_dofs_global();
  o.n_vertices = space.n_vertices_global();
  o.nodes = space.canonical_coords();
  o.cells = space.canonical_cells();
  if (target) {
    nl.reset();
    t0 = core::now_seconds();
    const auto tr = nl.solve_for_target(*target);
    o.t_target = core::now_seconds() - t0;
    o.target_newton = tr.newton_iterations;
    o.target_solves = tr.solves;
  }
  set_linear_solver(false);
  return o;
}

/// The vertices of a solved mesh (the label's nodes), n x 3.
std::span<const double> vertices(const Solved& s) { return {s.nodes.data(), std::size_t(s.n_vertices) * 3}; }

/// `from`'s solution at `points`.
std::vector<double> sample(const Solved& from, std::span<const double> points) {
  const sampling::MeshSampler sampler(3, 2, from.nodes, from.cells, from.shape.boundary, points);
  return sampler.interpolate(from.u, 3);
}

/// Lumped volumes of the label's vertices (a quarter of each tetrahedron around).
std::vector<double> vertex_volumes(const mesh::MeshData& m) {
  std::vector<double> w(std::size_t(m.n_vertices()), 0.0);
  for (std::int64_t c = 0; c < m.n_cells(); ++c) {
    const int* v = &m.cells[std::size_t(c) * 4];
    const double* x0 = &m.coords[std::size_t(v[0]) * 3];
    double e[3][3];
    for (int a = 0; a < 3; ++a)
      for (int k = 0; k < 3; ++k) e[a][k] = m.coords[std::size_t(v[a + 1]) * 3 + k] - x0[k];
    const double vol = std::abs(e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) -
                                e[0][1] * (e[1][0] * e[2][2] - e[1][2] * e[2][0]) +
                                e[0][2] * (e[1][0] * e[2][1] - e[1][1] * e[2][0])) / 6.0;
    for (int a = 0; a < 4; ++a) w[std::size_t(v[a])] += vol / 4;
  }
  return w;
}

/// Errors of `u` against `ref` at the label's vertices (both n x 3).
json errors(std::span<const double> u, std::span<const double> ref, const std::vector<double>& w, double ref_max) {
  double d2 = 0, r2 = 0, wd2 = 0, wr2 = 0, max_u = 0, worst = 0;
  std::size_t i_worst = 0;
  for (std::size_t i = 0; i < w.size(); ++i) {
    double dd = 0, rr = 0, uu = 0;
    for (int k = 0; k < 3; ++k) {
      dd += std::pow(u[3 * i + k] - ref[3 * i + k], 2);
      rr += ref[3 * i + k] * ref[3 * i + k];
      uu += u[3 * i + k] * u[3 * i + k];
    }
    d2 += dd, r2 += rr, wd2 += w[i] * dd, wr2 += w[i] * rr;
    if (dd > worst) worst = dd, i_worst = i;
    max_u = std::max(max_u, std::sqrt(uu));
  }
  return {{"rel_l2_nodal", std::sqrt(d2 / r2)},
          {"rel_l2_volume", std::sqrt(wd2 / wr2)},
          {"label_max_u", max_u},
          {"max_u_rel_error", max_u / ref_max - 1},
          {"max_nodal_error", std::sqrt(worst)},
          {"worst_vertex", i_worst},
          {"worst_u", {u[3 * i_worst], u[3 * i_worst + 1], u[3 * i_worst + 2]}},
          {"worst_u_ref", {ref[3 * i_worst], ref[3 * i_worst + 1], ref[3 * i_worst + 2]}}};
}

/// min and max |x| over the surface points (the ball: how far the surface is off the sphere).
std::array<double, 2> radius_range(const geometry::Boundary& b) {
  std::array<double, 2> r{1e300, 0};
  for (std::int64_t i = 0; i < b.n_points(); ++i) {
    const double* x = &b.points[std::size_t(i) * 3];
    const double n = std::sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
    r = {std::min(r[0], n), std::max(r[1], n)};
  }
  return r;
}

/// Area of the clamped facets (the ball's cap |x - p_D| <= 0.4: 2 pi 0.08 = 0.5027).
double clamp_area(const factory::ShapeSample& s) {
  double a = 0;
  for (int f : s.dirichlet_facets) {
    const auto t = s.boundary.facet(f);
    const double* p = &s.boundary.points[std::size_t(t[0]) * 3];
    const double* q = &s.boundary.points[std::size_t(t[1]) * 3];
    const double* w = &s.boundary.points[std::size_t(t[2]) * 3];
    const double u[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]}, v[3] = {w[0] - p[0], w[1] - p[1], w[2] - p[2]};
    const double c[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    a += 0.5 * std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
  }
  return a;
}

json describe(const Discretisation& d, const Solved& s, int loads_per_shape, double t_sample) {
  const double per_shape = s.t_mesh + s.t_setup;
  const double solve_time = std::isfinite(s.t_target) ? s.t_target : s.t_solve;
  const double per_load = d.per_load() ? solve_time + per_shape + t_sample : solve_time + per_shape / loads_per_shape;
  return {{"name", d.name},
          {"surface_h", d.surface_h},
          {"interior_h", d.interior_h},
          {"rim_size", d.rim_size},
          {"load_size", d.load_size},
          {"grading", d.grading},
          {"per_load_case_mesh", d.per_load()},
          {"label_on", d.label_on.empty() ? d.name : d.label_on},
          {"dofs", s.dofs},
          {"vertices", s.n_vertices},
          {"surface_points", s.shape.boundary.n_points()},
          {"surface_radius_range", radius_range(s.shape.boundary)},
          {"clamp_area", clamp_area(s.shape)},
          {"converged", s.converged},
          {"reason", s.reason},
          {"newton_iterations", s.newton},
          {"max_u", s.max_u},
          {"min_det_F", s.min_det_f},
          {"seconds_mesh", s.t_mesh},
          {"seconds_setup", s.t_setup},
          {"seconds_solve_alpha", s.t_solve},
          {"seconds_solve_target", std::isfinite(s.t_target) ? json(s.t_target) : json(nullptr)},
          {"target_newton_iterations", s.target_newton},
          {"target_solves", s.target_solves},
          {"seconds_sample", t_sample},
          {"seconds_per_load_case", per_load}};
}

/// The scene as a scene file would say it (for scripts/check_labels3d_dolfinx.py).
std::string scene_text(const Scene& s, double alpha) {
  auto v = [](const std::array<double, 3>& a) { return fmt::format("[{:.17g}, {:.17g}, {:.17g}]", a[0], a[1], a[2]); };
  return fmt::format(
      "geometry: {{base: file}}\nmesh: {{degree: 2}}\neffects:\n  neo_hookean: {{E: {:.17g}, nu: {:.17g}}}\n"
      "  dirichlet_patch: {{center: {}, radius: {:.17g}}}\n"
      "  gaussian_traction: {{center: {}, direction: {}, gamma: {:.17g}}}\nload: {{alpha: {:.17g}}}\n",
      s.cfg.material.E, s.cfg.material.nu, v(s.p_d), s.r, v(s.lc.center), v(s.lc.direction), s.cfg.loads.gamma, alpha);
}

void write_solved(const std::string& path, const Scene& scene, const Solved& s, double alpha) {
  io::SolutionRecord r;
  r.dim = 3;
  r.degree = 2;
  r.n_vertices = s.n_vertices;
  r.nodes = s.nodes;
  r.cells = s.cells;
  r.displacement = s.u;
  r.scene_text = scene_text(scene, alpha);
  r.numbers = {{"alpha", alpha}, {"max_displacement", s.max_u}, {"converged", s.converged ? 1.0 : 0.0},
               {"newton_iterations", double(s.newton)}};
  io::write_solution(path, r);
}

}  // namespace

json run(const Options& opt) {
  const Scene scene = make_scene(opt.scene);
  std::map<std::string, std::unique_ptr<Solved>> solved;
  std::map<std::string, Discretisation> by_name;
  for (const auto& d : opt.discretisations) by_name[d.name] = d;
  if (!by_name.contains(opt.reference)) throw std::invalid_argument("reference '" + opt.reference + "' is not among the discretisations");
  json out = {{"scene", opt.scene},
              {"alpha", opt.alpha},
              {"reference", opt.reference},
              {"p_D", scene.p_d},
              {"r", scene.r},
              {"p_N", scene.lc.center},
              {"g", scene.lc.direction},
              {"loads_per_shape", opt.loads_per_shape},
              {"E", scene.cfg.material.E},
              {"nu", scene.cfg.material.nu},
              {"gamma", scene.cfg.loads.gamma},
              {"results", json::array()}};
  // The reference first (its max|u| is the target of the timed target solves).
  std::vector<Discretisation> order{by_name[opt.reference]};
  for (const auto& d : opt.discretisations)
    if (d.name != opt.reference) order.push_back(d);
  std::optional<double> target;
  for (const auto& d : order) {
    if (!d.label_on.empty() && !solved.contains(d.label_on))
      throw std::invalid_argument(d.name + ": label_on '" + d.label_on + "' must come earlier");
    std::cerr << fmt::format("[labels3d] {} {} ...\n", opt.scene, d.name);
    std::unique_ptr<Solved> s;
    try {
      s = std::make_unique<Solved>(solve(scene, d, opt.alpha, opt.time_target ? target : std::nullopt));
    } catch (const std::exception& e) {
      // An option whose mesh cannot be made (e.g. a remeshing that folds a triangle) is a result
      // of the study, not its end; without the reference there is nothing to compare.
      if (d.name == opt.reference) throw;
      set_linear_solver(false);
      std::cerr << fmt::format("[labels3d]   {} failed: {}\n", d.name, e.what());
      out["results"].push_back({{"name", d.name}, {"converged", false}, {"reason", std::string("failed: ") + e.what()}});
      continue;
    }
    if (d.name == opt.reference) target = s->max_u;
    if (!opt.write_dir.empty()) write_solved(opt.write_dir + "/" + opt.scene + "_" + d.name + ".h5", scene, *s, opt.alpha);
    solved.emplace(d.name, std::move(s));
    const Solved& ref = *solved.at(opt.reference);
    const Solved& me = *solved.at(d.name);
    const Solved& label = d.label_on.empty() ? me : *solved.at(d.label_on);
    const double t0 = core::now_seconds();
    // The label at its vertices: the nodal values (vertices come first), or sampled.
    std::vector<double> u = d.label_on.empty() ? std::vector<double>(me.u.begin(), me.u.begin() + 3 * me.n_vertices)
                                               : sample(me, vertices(label));
    const double t_sample = d.label_on.empty() ? 0.0 : core::now_seconds() - t0;
    json r = describe(d, me, opt.loads_per_shape, t_sample);
    r["label_vertices"] = label.n_vertices;
    if (me.converged && ref.converged) {
      const std::vector<double> u_ref = sample(ref, vertices(label));
      r["error"] = errors(u, u_ref, vertex_volumes(label.shape.mesh), ref.max_u);
      const auto iw = r["error"]["worst_vertex"].get<std::size_t>();
      r["error"]["worst_x"] = {label.nodes[3 * iw], label.nodes[3 * iw + 1], label.nodes[3 * iw + 2]};
    }
    std::cerr << fmt::format("[labels3d]   {} dofs, {} Newton, max|u| {:.5g}, {:.1f}+{:.1f}+{:.1f} s, {}\n", me.dofs,
                             me.newton, me.max_u, me.t_mesh, me.t_setup, me.t_solve,
                             r.contains("error") ? r["error"].dump() : me.reason);
    out["results"].push_back(r);
    // Per-load-case solutions are not labels of anything: free them.
    if (d.per_load() && d.name != opt.reference) solved.erase(d.name);
  }
  return out;
}

}  // namespace hypershape::study::labels3d
