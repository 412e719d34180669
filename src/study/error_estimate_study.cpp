// Validation of the labels' error estimate (see include/hypershape/study/error_estimate_study.hpp).
#include "hypershape/study/error_estimate_study.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <iostream>

#include "accuracy_detail.hpp"
#include "hypershape/core/timer.hpp"
#include "hypershape/factory/accuracy.hpp"
#include "hypershape/factory/dataset_scene.hpp"
#include "hypershape/factory/label_error.hpp"

namespace hypershape::study {

namespace {

using accuracy::json;

/// One reference level: the scene on the mesh refined once more than the level before.
struct Level {
  mesh::RefinedMesh refined;
  factory::ShapeSample shape;
  factory::ShapeProblem problem;
  std::unique_ptr<solver::TwoLevelEstimator> from_coarser;  ///< prolongation from the level before
  std::unique_ptr<solver::NonlinearSolver> nl;
};

double norm2(const physics::Space& s, const std::vector<double>& v) {
  return std::sqrt(solver::l2_norm_squared(s.dim(), s.degree(), s.canonical_coords(), s.canonical_cells(), v, s.dim()));
}

double max_norm(const std::vector<double>& v, int d) {
  double m = 0;
  for (std::size_t i = 0; i + std::size_t(d) <= v.size(); i += std::size_t(d)) {
    double a = 0;
    for (int k = 0; k < d; ++k) a += v[i + std::size_t(k)] * v[i + std::size_t(k)];
    m = std::max(m, std::sqrt(a));
  }
  return m;
}

std::vector<double> axpy(double a, const std::vector<double>& x, const std::vector<double>& y) {
  std::vector<double> out(y);
  for (std::size_t i = 0; i < out.size(); ++i) out[i] += a * x[i];
  return out;
}

/// Observed order from two successive differences, clamped to [0.5, 4] (as the accuracy study).
double observed_order(double coarse_diff, double fine_diff) {
  if (!(coarse_diff > 0) || !(fine_diff > 0)) return 4.0;
  return std::clamp(std::log2(coarse_diff / fine_diff), 0.5, 4.0);
}

/// The reference solutions of one load case at the coarse alpha, prolonged to the finest level,
/// with alpha for the target at every level. False (and `why`) if a reference solve failed.
bool solve_references(std::vector<Level>& levels, const config::DatasetConfig& cfg, const factory::LoadCase& lc,
                      double alpha_h, std::vector<std::vector<double>>& u, std::vector<double>& alphas,
                      std::string& why) {
  for (std::size_t k = 0; k < levels.size(); ++k) {
    Level& L = levels[k];
    L.problem.set_load_case(cfg, L.shape, lc);
    L.nl->reset();
    const auto t = L.nl->solve_for_target(lc.target);
    if (!t.converged) return why = fmt::format("level {} target: {}", k + 1, t.reason), false;
    alphas.push_back(t.alpha);
    const auto s = L.nl->solve(alpha_h);  // from the target state: a small change of load
    if (!s.converged) return why = fmt::format("level {} same load: {}", k + 1, s.reason), false;
    u.push_back(L.problem.problem->gather(L.nl->solution()).values);
  }
  // Prolong every level to the finest.
  for (std::size_t k = 0; k + 1 < u.size(); ++k)
    for (std::size_t j = k + 1; j < levels.size(); ++j) u[k] = levels[j].from_coarser->prolong(u[k]);
  return true;
}

/// The true errors of one case from the references (see the header), into `j`.
void true_errors(const std::vector<Level>& levels, std::vector<double> uh, const std::vector<std::vector<double>>& u,
                 const std::vector<double>& alphas, double alpha_h, int p, json& j) {
  const physics::Space& fs = levels.back().problem.problem->space();
  const int d = fs.dim();
  for (const auto& L : levels) uh = L.from_coarser->prolong(uh);
  const std::vector<double>& uf = u.back();
  double q = p + 1, qa = 1.0;
  std::vector<double> uext = uf;
  double aext = alphas.back();
  if (u.size() >= 2) {
    q = observed_order(norm2(fs, axpy(-1, uh, u[u.size() - 2])), norm2(fs, axpy(-1, u[u.size() - 2], uf)));
    qa = observed_order(std::abs(alphas[alphas.size() - 2] - alpha_h), std::abs(alphas.back() - alphas[alphas.size() - 2]));
    uext = axpy(1.0 / (std::pow(2.0, q) - 1), axpy(-1, u[u.size() - 2], uf), uf);
    aext = alphas.back() + (alphas.back() - alphas[alphas.size() - 2]) / (std::pow(2.0, qa) - 1);
  } else {  // one level: the order assumed (p + 1 for u; 1 for alpha, the clamp ends' rate)
    uext = axpy(1.0 / (std::pow(2.0, q) - 1), axpy(-1, uh, uf), uf);
    aext = alphas.back() + (alphas.back() - alpha_h) / (std::pow(2.0, qa) - 1);
  }
  const double mh = max_norm(uh, d);
  j["true_rel_l2"] = norm2(fs, axpy(-1, uh, uext)) / norm2(fs, uext);
  j["true_rel_l2_finest"] = norm2(fs, axpy(-1, uh, uf)) / norm2(fs, uf);
  j["true_max_u"] = (max_norm(uext, d) - mh) / mh;
  j["true_alpha"] = (aext - alpha_h) / alpha_h;
  j["observed_order_u"] = q;
  j["observed_order_alpha"] = qa;
  j["reference_alphas"] = alphas;
  j["order_assumed"] = u.size() < 2;
}

/// Solves and estimates every load case of one shape and measures the truth, a line each.
void run_shape(const config::DatasetConfig& cfg, const factory::ShapeSample& shape,
               const std::vector<factory::LoadCase>& cases, int n_levels, bool fine_newton, const std::string& label,
               std::ostream& out) {
  const MPI_Comm comm = PETSC_COMM_WORLD;
  const double t_setup = core::now_seconds();
  factory::ShapeProblem sp = factory::make_shape_problem(comm, cfg, shape, cases[0]);
  solver::NonlinearSolver nl(*sp.problem, cfg.solver);
  const double t_est0 = core::now_seconds();
  factory::LabelErrorEstimator est(comm, cfg, shape, cases[0], *sp.problem, fine_newton);
  const double est_setup = core::now_seconds() - t_est0;
  std::vector<Level> levels(static_cast<std::size_t>(n_levels));
  const mesh::MeshData* coarser = &shape.mesh;
  const physics::Problem* coarser_problem = sp.problem.get();
  for (auto& L : levels) {
    L.refined = mesh::refine_uniform(*coarser);
    L.shape.shape_id = shape.shape_id;
    L.shape.dirichlet_center = shape.dirichlet_center;
    L.shape.dirichlet_radius = shape.dirichlet_radius;
    L.shape.mesh = L.refined.mesh;
    L.problem = factory::make_shape_problem(comm, cfg, L.shape, cases[0]);
    L.from_coarser = std::make_unique<solver::TwoLevelEstimator>(*coarser_problem, *L.problem.problem, L.refined);
    L.nl = std::make_unique<solver::NonlinearSolver>(*L.problem.problem, cfg.solver, "ref_");
    coarser = &L.shape.mesh;
    coarser_problem = L.problem.problem.get();
  }
  std::cerr << fmt::format("[estimate study] {} shape {}: {} dofs, references {} (set-up {:.1f} s)\n", label,
                           shape.shape_id, sp.problem->space().n_dofs_global(),
                           levels.empty() ? 0 : levels.back().problem.problem->space().n_dofs_global(),
                           core::now_seconds() - t_setup);
  for (const auto& lc : cases) {
    json j{{"case", label}, {"dim", cfg.shapes.dim}, {"degree", sp.problem->space().degree()},
           {"shape", shape.shape_id}, {"load", lc.load_id}, {"target", lc.target},
           {"n_dofs", sp.problem->space().n_dofs_global()}, {"estimator_setup_seconds", est_setup}};
    sp.set_load_case(cfg, shape, lc);
    nl.reset();
    const auto r = nl.solve_for_target(lc.target);
    j["converged"] = r.converged;
    j["solve_seconds"] = r.seconds_total;
    j["solve_tangent_assemblies"] = r.linear.tangent_assemblies;
    j["solve_factorizations"] = r.linear.numeric_factorizations;
    j["newton_iterations"] = r.newton_iterations;
    if (r.converged) {
      const auto e = est.estimate(cfg, lc, nl.solution(), r.alpha,
                                  [&](Vec x, Vec y, bool refined) { return nl.apply_tangent_factor(x, y, refined); });
      j["alpha"] = r.alpha;
      j["estimate_ok"] = e.ok;
      j["est_rel_l2"] = e.rel_l2;
      j["est_raw_rel_l2"] = e.raw_rel_l2;
      j["est_max_u"] = e.max_u;
      j["est_alpha"] = e.alpha;
      j["estimate_seconds"] = e.seconds;
      j["estimate_seconds_assembly"] = e.seconds_assembly;
      j["estimate_seconds_linear"] = e.seconds_linear;
      j["estimate_krylov_iterations"] = e.krylov_iterations;
      j["est_raw_max_u"] = e.raw_max_u;
      j["est_slope"] = e.slope;
      j["estimate_newton_converged"] = e.newton_steps_converged;
      j["estimate_krylov_budget_spent"] = e.krylov_budget_spent;
      j["estimate_tangent_assemblies"] = e.tangent_assemblies;
      j["estimate_residual_assemblies"] = e.residual_assemblies;
      j["estimate_relaxations"] = e.relaxations;
      std::vector<std::vector<double>> u;
      std::vector<double> alphas;
      std::string why;
      if (levels.empty())
        ;  // --estimate-only
      else if (solve_references(levels, cfg, lc, r.alpha, u, alphas, why))
        true_errors(levels, sp.problem->gather(nl.solution()).values, u, alphas, r.alpha, sp.problem->space().degree(), j);
      else
        j["reference_failed"] = why;
    }
    out << j.dump() << std::endl;
    std::cerr << fmt::format("[estimate study]   load {}: est {:.3g} true {:.3g}\n", lc.load_id,
                             j.value("est_rel_l2", NAN), j.value("true_rel_l2", NAN));
  }
}

}  // namespace

void run_estimate_study(const EstimateStudyOptions& o, std::ostream& out) {
  const std::vector<accuracy::SceneSpec>& scenes = accuracy::study_scenes();
  auto spec = std::find_if(scenes.begin(), scenes.end(), [&](const auto& s) { return s.name == o.scene; });
  if (!o.scene.empty() && spec == scenes.end())
    throw std::invalid_argument("--scene: one of disk r2d-0 r2d-1 ood-0 easy-0 ball r3d-0, got " + o.scene);
  config::DatasetConfig cfg = o.scene.empty()
                                  ? config::parse_dataset_text("preset: " + o.preset + "\n", "<study_error_estimate>")
                                  : accuracy::scene_config(*spec, "");
  if (o.degree) cfg.degree = o.degree;
  const int d = cfg.shapes.dim;
  if (o.h > 0) (d == 3 && cfg.shapes.mesh_h > 0 ? cfg.shapes.mesh_h : cfg.shapes.h) = o.h;
  const int n_levels = !o.references ? 0 : o.levels > 0 ? o.levels : (d == 2 ? 2 : 1);
  if (o.graded >= 0 && (d != 2 || !o.scene.empty())) throw std::invalid_argument("--graded: 2D random shapes only");
  if (o.graded >= 0) cfg.shapes.rim_size = o.graded * cfg.shapes.h;  // made by make_shape, as the factory does
  const std::string label = fmt::format("{}-P{}-h{:g}{}{}", o.scene.empty() ? o.preset : o.scene, cfg.degree,
                                        accuracy::preset_mesh_h(cfg), o.graded >= 0 ? fmt::format("-graded{:g}", o.graded) : "",
                                        o.fine_newton ? "-fine-newton" : "");
  if (!o.scene.empty()) {
    const double h = accuracy::preset_mesh_h(cfg);
    accuracy::ShapeCache cache(spec->kind, cfg.shapes, cfg.seed, spec->shape_id, std::min(h, cfg.shapes.h));
    const auto& shape = cache.at(h);
    auto loads = cfg.loads;
    loads.count = 3;
    auto cases = factory::draw_load_cases(cache.at(cfg.shapes.h), loads, cfg.seed);
    const double targets[3] = {0.1, 0.3, 0.5};
    for (std::size_t l = 0; l < cases.size(); ++l) cases[l].target = targets[l];
    cases.resize(std::size_t(std::min(o.loads, 3)));
    run_shape(cfg, shape, cases, n_levels, o.fine_newton, label, out);
    return;
  }
  const auto base = factory::load_base(cfg.shapes);
  for (std::int64_t id : o.shapes) {
    const auto shape = factory::make_shape(factory::shape_config(cfg, id), base, cfg.seed, id);
    auto cases = factory::draw_load_cases(shape, cfg.loads, cfg.seed, factory::n_tractions(cfg));
    cases.resize(std::size_t(std::min<int>(o.loads, int(cases.size()))));
    run_shape(cfg, shape, cases, n_levels, o.fine_newton, label, out);
  }
}

}  // namespace hypershape::study
