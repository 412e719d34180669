// The settings of the accuracy study and how each is measured against the reference.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <tuple>

#include "accuracy_detail.hpp"
#include "hypershape/core/timer.hpp"
#include "hypershape/study/output.hpp"
#include "hypershape/study/stats.hpp"

namespace hypershape::study::accuracy {

namespace {

/// Collects the settings of one scene: each one the baseline with some knobs turned.
struct SettingsBuilder {
  int dim;
  double h0;
  int p0;
  Setting base;
  std::vector<Setting> out;

  void add(Setting s) {
    s.baseline_discretisation =
        s.h == h0 && s.degree == p0 && s.quadrature == base.quadrature && !s.linear_model && s.load_rotation == 0;
    s.is_default = s.group == "mesh" && s.h == h0 && s.degree == p0;
    // 3D: MUMPS everywhere beyond kAutoMumpsDofs, the baseline included: PETSc's own Cholesky
    // (the one-rank default) took 233 s for one load case of the ball at P1 h 0.1 (25k unknowns,
    // 3 Newton iterations) where MUMPS LDL^T took 6.8 s (docs/ACCURACY.md).
    s.auto_solver = dim == 3 || !(s.h == h0 && s.degree == p0);
    out.push_back(std::move(s));
  }
  template <class Change>
  void knob(const std::string& group, const std::string& what, Change&& change) {
    Setting s = base;
    change(s);
    s.name = fmt::format("P{} h{} {}", s.degree, fmt_g(s.h), what);
    s.group = group;
    add(s);
  }
};

/// The h x degree grid (P2 only coarser than the reference's mesh).
void add_mesh_grid(SettingsBuilder& b, std::vector<double> sizes, double ref_h) {
  std::sort(sizes.begin(), sizes.end(), std::greater<>());
  for (int p : {1, 2})
    for (double h : sizes) {
      if (p == 2 && h <= ref_h * 1.0001) continue;  // the reference's mesh or finer
      Setting s = b.base;
      s.degree = p;
      s.h = h;
      s.name = fmt::format("P{} h{}{}", p, fmt_g(h), s.quadrature ? fmt::format(" quad {}", s.quadrature) : "");
      s.group = "mesh";
      b.add(s);
    }
}

/// 2D: the linear model at P2, quadrature, tolerances, control and (disk) the p_D diagnostic.
void add_knobs_2d(SettingsBuilder& b, double ref_h, SceneKind scene_kind) {
  b.knob("linear_model", "linear", [](Setting& s) {
    s.linear_model = true;
    s.degree = 2;
  });
  // Quadrature: only P2 has a choice that matters (P1 gradients are constant per cell).
  for (int q : {2, 4, 6})
    b.knob("quadrature", fmt::format("quad {}", q), [q](Setting& s) {
      s.degree = 2;
      s.h = 0.08;
      s.quadrature = q;
    });
  for (double rtol : {1e-6, 1e-12})
    b.knob("newton_rtol", fmt::format("rtol {:g}", rtol), [rtol](Setting& s) { s.opt.rtol = rtol; });
  for (double t : {1e-2, 1e-4})
    b.knob("target_rtol", fmt::format("target_rtol {:g}", t), [t](Setting& s) { s.opt.target_rtol = t; });
  b.knob("control", "load control", [](Setting& s) { s.opt.control = solver::Control::load; });
  b.knob("path_rtol", "path_rtol 0.01", [](Setting& s) { s.opt.path_rtol = 1e-2; });
  if (scene_kind == SceneKind::disk)
    // How much a small move of p_D alone changes u (the p_D of random 2D shapes moves with h):
    // on the reference's own mesh and on the default's.
    for (auto [p, h] : {std::pair{1, b.h0}, std::pair{2, ref_h}})
      b.knob("diagnostic", "p_D moved 0.003", [p = p, h = h, g = p == 2](Setting& s) {
        s.degree = p;
        s.h = h;
        s.graded = g;  // P2: on the reference's own mesh, so only p_D differs
        s.load_rotation = -0.003;
      });
}

void add_linear_solvers(SettingsBuilder& b) {
  std::vector<std::pair<std::string, PetscOptionList>> solvers{
      {"mumps cholesky", mumps_cholesky()},
      {"mumps lu", {{"pc_type", "lu"}, {"pc_factor_mat_solver_type", "mumps"}}},
      {"gmres+gamg", {{"ksp_type", "gmres"}, {"pc_type", "gamg"}, {"ksp_rtol", "1e-8"}, {"ksp_max_it", "2000"}}},
      {"gmres+hypre",
       {{"ksp_type", "gmres"},
        {"pc_type", "hypre"},
        {"pc_hypre_type", "boomeramg"},
        {"pc_hypre_boomeramg_strong_threshold", "0.5"},
        {"ksp_rtol", "1e-8"},
        {"ksp_max_it", "2000"}}},
  };
  for (const auto& [name, opts] : solvers) {
    // 3D: MUMPS LDL^T is the baseline there; LU and GAMG (about 155 Krylov iterations per
    // Newton step on 3D P2, FACTS.md) are left out for time.
    if (b.dim == 3 && name != "gmres+hypre") continue;
    b.knob("linear_solver", name, [&opts = opts](Setting& s) { s.petsc = opts; });
  }
}

}  // namespace

/// The settings of one scene: the baseline = the preset's defaults (h, degree, SolverOptions,
/// the one-rank linear solver), the h x degree grid, and one knob at a time from the baseline.
/// 3D runs the grid, the linear model and two linear solvers only (each 3D solve costs seconds
/// to minutes here; the tolerance and continuation knobs act the same way in 2D and 3D).
std::vector<Setting> make_settings(int dim, const AccuracyOptions& a, const config::DatasetConfig& cfg, double ref_h,
                                   SceneKind scene_kind) {
  SettingsBuilder b{dim, preset_mesh_h(cfg), cfg.degree, {}, {}};
  b.base.degree = b.p0;
  b.base.h = b.h0;
  b.base.opt = cfg.solver;
  b.base.quadrature = cfg.quadrature;  // an --override of mesh.quadrature: every setting's rule, not the reference's
  // First: the baseline discretisation at tight tolerances (the solver-error yardstick).
  if (dim == 2)
    b.knob("tolerance", "tight", [](Setting& s) {
      s.opt.rtol = 1e-10;
      s.opt.target_rtol = 1e-6;
    });
  add_mesh_grid(b, a.tiny ? std::vector<double>{0.16, 0.08, 0.04} : dim == 2 ? a.sizes2d : a.sizes3d, ref_h);
  b.knob("linear_model", "linear", [](Setting& s) { s.linear_model = true; });
  if (a.tiny || a.grid_only) return b.out;
  if (dim == 2) add_knobs_2d(b, ref_h, scene_kind);
  add_linear_solvers(b);
  return b.out;
}

json setting_json(const Setting& s) {
  json j;
  j["name"] = s.name;
  j["group"] = s.group;
  j["degree"] = s.degree;
  j["h"] = s.h;
  j["quadrature_degree"] = s.quadrature == 0 ? 2 * s.degree - 1 : s.quadrature;
  j["rtol"] = s.opt.rtol;
  j["target_rtol"] = s.opt.target_rtol;
  j["control"] = s.opt.control == solver::Control::displacement ? "displacement" : "load";
  j["path_rtol"] = s.opt.path_rtol;
  json p = json::object();
  for (const auto& [k, v] : s.petsc) p["-" + k] = v;
  j["petsc"] = p;
  j["linear_model"] = s.linear_model;
  j["load_rotation"] = s.load_rotation;
  j["graded"] = s.graded;
  j["is_default"] = s.is_default;
  return j;
}

namespace {

/// The settings loop of one scene: its state across settings.
struct SettingsPass {
  Scene& s;
  const Reference& ref;
  json& sc;
  std::vector<SameLoad>& same_load;  ///< the settings' answers, for the same-load pass
  std::vector<std::vector<double>> tight_u;  ///< baseline discretisation at tight tolerances, per load
  bool dumped = false;
};

/// How far this shape is from the reference's: boundary points vs the reference boundary.
void add_shape_gap(const SettingsPass& p, const factory::ShapeSample& shape, json& r) {
  std::vector<double> dist(std::size_t(shape.boundary.n_points()));
  p.ref.sdf->evaluate(shape.boundary.points, dist);
  double gap = 0;
  for (double x : dist) gap = std::max(gap, std::abs(x));
  double pd = 0;
  for (int k = 0; k < p.s.d; ++k)
    pd += std::pow(shape.dirichlet_center[std::size_t(k)] - p.ref.record["dirichlet_center"][std::size_t(k)].get<double>(),
                   2);
  r["boundary_gap"] = gap;
  r["dirichlet_center_offset"] = std::sqrt(pd);
}

/// --dump: the arrays of the first P1 mesh setting and the reference (the tiny test's check).
void dump_arrays(SettingsPass& p, const Setting& st, std::size_t l, const std::vector<double>& u_hat, double e2,
                 double e1) {
  if (p.s.a.dump.empty() || p.dumped || st.group != "mesh" || st.degree != 1) return;
  json dj{{"dim", p.s.d},          {"setting", st.name},         {"nodes", p.ref.nodes},
          {"cells", p.ref.cells},  {"nodes_per_cell", p.ref.nodes_per_cell}, {"u_ref", p.ref.u[l]},
          {"u_hat", u_hat},        {"rel_l2", e2},               {"rel_h1", e1}};
  write_json_atomic(p.s.a.dump, dj, "--dump", 1);
  p.dumped = true;
}

/// The errors of a converged load case against the reference, into `lj` and the lists.
void add_errors(SettingsPass& p, const Setting& st, std::size_t l, const LoadOutcome& lo,
                const std::vector<double>& u_hat, json& lj, std::vector<std::vector<double>*> lists) {
  const int d = p.s.d;
  const double e2 = p.ref.norms->rel_l2(p.ref.u[l], u_hat, d);
  const double e1 = p.ref.norms->rel_h1(p.ref.u[l], u_hat, d);
  const double ea = std::abs(lo.alpha - p.ref.alpha[l]) / p.ref.alpha[l];
  lj["rel_l2"] = number_or_null(e2);
  lj["rel_h1"] = number_or_null(e1);
  lj["alpha_err"] = number_or_null(ea);
  lj["max_u_err"] = number_or_null(std::abs(lo.max_u / p.s.cases[l].target - 1.0));
  lists[0]->push_back(e2), lists[1]->push_back(e1), lists[2]->push_back(ea);
  p.same_load.push_back({p.sc["results"].size(), l, lo.alpha, u_hat});
  const bool is_tight = st.group == "tolerance" && st.baseline_discretisation;
  if (is_tight) p.tight_u[l] = lo.u;
  if (st.baseline_discretisation && !is_tight && p.tight_u[l].size() == lo.u.size()) {
    const double se = rel_l2_diff(lo.u, p.tight_u[l], p.tight_u[l], d);
    lj["solver_l2"] = number_or_null(se);
    lists[3]->push_back(se);
  }
  dump_arrays(p, st, l, u_hat, e2, e1);
}

json load_json(const LoadOutcome& lo) {
  return {{"converged", lo.converged},
          {"reason", lo.reason},
          {"alpha", number_or_null(lo.alpha)},
          {"max_u", number_or_null(lo.max_u)},
          {"seconds", number_or_null(lo.seconds)},
          {"seconds_all", lo.seconds_all},
          {"cpu_seconds", number_or_null(lo.cpu_seconds)},
          {"cpu_seconds_all", lo.cpu_seconds_all},
          {"newton", lo.newton},
          {"newton_all", lo.newton_all},
          {"solves", lo.solves},
          {"failed_increments", lo.failed_increments}};
}

/// Per load case: outcome and errors (r["loads"]); then the setting's summary.
void add_loads(SettingsPass& p, const Setting& st, const factory::ShapeSample& shape, const SolvedSetting& solved,
               json& r) {
  const auto at_ref = at_reference(shape, solved, p.ref, p.s.d);
  const std::size_t n = p.s.cases.size();
  json per = json::array();
  std::vector<double> l2s, h1s, aes, secs, cpus, sol;
  int n_ok = 0;
  for (std::size_t l = 0; l < n; ++l) {
    const auto& lo = solved.loads[l];
    json lj = load_json(lo);
    if (lo.converged) {
      ++n_ok;
      add_errors(p, st, l, lo, at_ref[l], lj, {&l2s, &h1s, &aes, &sol});
    }
    secs.push_back(lo.seconds);
    cpus.push_back(lo.cpu_seconds);
    per.push_back(lj);
  }
  r["loads"] = per;
  const double amort = (p.s.shapes->seconds(st.h, st.graded) + solved.seconds_setup) / p.s.cfg.loads.count;
  const bool all = n_ok == int(n);
  r["summary"] = {{"loads", int(n)},
                  {"converged", n_ok},
                  {"rel_l2", number_or_null(all ? finite_mean(l2s) : NAN)},
                  {"rel_h1", number_or_null(all ? finite_mean(h1s) : NAN)},
                  {"alpha_err", number_or_null(all ? finite_mean(aes) : NAN)},
                  {"solver_l2", number_or_null(finite_mean(sol))},
                  {"seconds_per_load", number_or_null(finite_mean(secs))},
                  {"cpu_seconds_per_load", number_or_null(finite_mean(cpus))},
                  {"seconds_per_load_amortised", number_or_null(finite_mean(secs) + amort)}};
  std::cerr << fmt::format("[study] {}: {:<34} {:>8} DoFs  {:>9}/load  rel L2 {:.2e}  H1 {:.2e}  alpha {:.2e}  "
                           "{}/{} ok\n",
                           p.s.spec.name, st.name, solved.dofs, fmt_s(r["summary"]["seconds_per_load"]),
                           finite_mean(l2s), finite_mean(h1s), finite_mean(aes), n_ok, n);
}

/// One setting solved and measured; throws on a failure of the setting as a whole.
void measure_setting(SettingsPass& p, const Setting& st, json& r) {
  Scene& s = p.s;
  const auto& shape = s.shapes->at(st.h, st.graded);
  check_same_draw(shape, *s.base_shape, st.h);
  auto solved = solve_setting(shape, s.cfg, s.cases, st, s.a.repeats, s.a.repeat_above,
                              fmt::format("s{}_", s.setting_counter++), s.a.verbose);
  if (!solved.error.empty()) throw std::runtime_error(solved.error);
  r["dofs"] = solved.dofs;
  r["linear_solver"] = solved.linear_solver;
  r["vertices"] = solved.n_vertices;
  r["cells"] = solved.n_cells;
  r["seconds_mesh"] = number_or_null(s.shapes->seconds(st.h, st.graded));
  r["seconds_setup"] = number_or_null(solved.seconds_setup);
  r["peak_rss_mib"] = number_or_null(solved.peak_rss_mib);
  r["rss_before_mib"] = number_or_null(solved.rss_before_mib);
  r["peak_rss_delta_mib"] = number_or_null(solved.peak_rss_mib - solved.rss_before_mib);
  add_shape_gap(p, shape, r);
  add_loads(p, st, shape, solved, r);
}

}  // namespace

void run_settings(Scene& s, const std::vector<Setting>& settings, const Reference& ref, json& sc,
                  std::vector<SameLoad>& same_load) {
  SettingsPass p{s, ref, sc, same_load, std::vector<std::vector<double>>(s.cases.size())};
  sc["results"] = json::array();
  for (const auto& st : settings) {
    json r;
    r["setting"] = setting_json(st);
    try {
      measure_setting(p, st, r);
    } catch (const std::exception& e) {
      r["error"] = e.what();
      r["summary"] = {{"loads", int(s.cases.size())}, {"converged", 0}, {"rel_l2", nullptr}, {"rel_h1", nullptr},
                      {"alpha_err", nullptr}, {"solver_l2", nullptr}, {"seconds_per_load", nullptr},
                      {"seconds_per_load_amortised", nullptr}};
      r["peak_rss_mib"] = nullptr;
      r["peak_rss_delta_mib"] = nullptr;
      std::cerr << fmt::format("[study] {}: {}: ERROR {}\n", s.spec.name, st.name, e.what());
    }
    sc["results"].push_back(r);
  }
}

}  // namespace hypershape::study::accuracy
