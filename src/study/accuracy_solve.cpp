// Solving one setting of the accuracy study: every load case, timed, repeated, gathered.
#include <petscksp.h>
#include <petscsnes.h>

#include <fmt/format.h>

#include <cmath>
#include <iostream>

#include "accuracy_detail.hpp"
#include "hypershape/core/error.hpp"
#include "hypershape/core/petsc_handle.hpp"
#include "hypershape/core/timer.hpp"
#include "hypershape/factory/dataset_scene.hpp"
#include "hypershape/study/stats.hpp"
#include "hypershape/study/timing.hpp"

namespace hypershape::study::accuracy {

PetscOptionList mumps_cholesky() { return {{"pc_type", "cholesky"}, {"pc_factor_mat_solver_type", "mumps"}}; }

namespace {

constexpr std::int64_t kAutoMumpsDofs = 20000;

/// PETSc options of this setting, under its own prefix (removed by the caller afterwards).
/// Beyond kAutoMumpsDofs unknowns, settings off the baseline mesh that do not choose a linear
/// solver get MUMPS LDL^T: with PETSc's own Cholesky (the one-rank default, fastest at the
/// default's ~5k unknowns) a Newton iteration of the disk at P2 h 0.02 (74k unknowns) took
/// 1.5 s, with MUMPS 0.6 s. Returns the linear solver's description.
std::string set_petsc_options(const physics::Problem& problem, const Setting& s, const std::string& prefix,
                              PetscOptionList& petsc) {
  if (petsc.empty() && s.auto_solver && problem.space().n_dofs_global() > kAutoMumpsDofs) petsc = mumps_cholesky();
  for (const auto& [k, v] : petsc)
    HS_PETSC(PetscOptionsSetValue(nullptr, ("-" + prefix + k).c_str(), v.empty() ? nullptr : v.c_str()));
  std::string out = petsc.empty() ? "petsc cholesky (default)" : "";
  for (const auto& [k, v] : petsc) out += (out.empty() ? "-" : " -") + k + " " + v;
  return out;
}

/// The load (p_N and g) rotated by `angle` about the origin (2D).
void rotate_load(factory::LoadCase& lc, double angle) {
  if (angle == 0) return;
  const double c = std::cos(angle), sn = std::sin(angle);
  for (auto* v : {&lc.center, &lc.direction}) {
    const double x = (*v)[0], y = (*v)[1];
    (*v)[0] = c * x - sn * y;
    (*v)[1] = sn * x + c * y;
  }
}

/// The small-strain model: u_lin = alpha_lin K(0)^-1 f_ext with alpha_lin = target /
/// max|K(0)^-1 f_ext| (NonlinearSolver::linear_response: one factorisation of the tangent at
/// u = 0 and one solve, on the solver's KSP), in `du`.
void linear_model(solver::NonlinearSolver& nl, const physics::Problem& problem, double target, Vec du,
                  LoadOutcome& lo) {
  const std::optional<double> m = nl.linear_response(du);
  if (!m) {
    lo.converged = false;
    lo.reason = "tangent at u = 0 not formed";
    return;
  }
  KSP ksp;
  HS_PETSC(SNESGetKSP(nl.snes(), &ksp));
  KSPConvergedReason why;
  HS_PETSC(KSPGetConvergedReason(ksp, &why));
  lo.converged = why > 0 && *m > 0 && std::isfinite(*m);
  lo.reason = KSPConvergedReasons[why];
  lo.alpha = target / *m;
  HS_PETSC(VecScale(du, lo.alpha));
  lo.max_u = problem.max_displacement(du);
  lo.solves = 1;
}

void nonlinear_model(solver::NonlinearSolver& nl, const physics::Problem& problem, double target, LoadOutcome& lo) {
  const auto tr = nl.solve_for_target(target);
  lo.converged = tr.converged;
  lo.reason = tr.reason;
  lo.alpha = tr.alpha;
  lo.max_u = problem.max_displacement(nl.solution());
  lo.newton = tr.newton_iterations;
  lo.solves = tr.solves;
  lo.failed_increments = tr.failed_increments;
}

/// What one setting solves with: the problem, its solver and the linear model's vector.
struct Solving {
  const factory::ShapeSample& shape;
  const config::DatasetConfig& cfg;
  const Setting& s;
  factory::ShapeProblem& sp;
  solver::NonlinearSolver& nl;
  Vec du;
};

/// One load case, `repeats` times (fewer after a failure or a run longer than repeat_above), each
/// from the first-increment hint the first one had: the medians of the wall and CPU times, and
/// the gathered displacement.
LoadOutcome solve_load(Solving& w, const factory::LoadCase& lc, int repeats, double repeat_above) {
  const physics::Problem& problem = *w.sp.problem;
  LoadOutcome lo;
  const double hint = w.nl.step_hint();  // the previous load case's, as the factory would see it
  for (int r = 0; r < repeats; ++r) {
    const double t1 = core::now_seconds(), c1 = cpu_seconds();
    w.sp.set_load_case(w.cfg, w.shape, lc);
    w.nl.reset();
    w.nl.set_step_hint(hint);
    if (w.s.linear_model)
      linear_model(w.nl, problem, lc.target, w.du, lo);
    else
      nonlinear_model(w.nl, problem, lc.target, lo);
    const double t = core::now_seconds() - t1;
    lo.seconds_all.push_back(t);
    lo.cpu_seconds_all.push_back(cpu_seconds() - c1);
    lo.newton_all.push_back(lo.newton);
    if (!lo.converged || t > repeat_above) break;
  }
  lo.seconds = median(lo.seconds_all);
  lo.cpu_seconds = median(lo.cpu_seconds_all);
  return lo;
}

/// The converged displacement of `lo`, gathered in canonical order (not converged if not finite).
void gather_displacement(Solving& w, LoadOutcome& lo) {
  if (!lo.converged) return;
  const auto f = w.sp.problem->gather(w.s.linear_model ? w.du : w.nl.solution());
  lo.u = f.values;
  for (double v : lo.u)
    if (!std::isfinite(v)) {
      lo.converged = false;
      lo.reason = "non-finite displacement";
      break;
    }
}

/// The space's sizes and canonical mesh.
void record_space(const physics::Problem& problem, SolvedSetting& out) {
  const auto& space = problem.space();
  out.dofs = space.n_dofs_global();
  out.n_vertices = space.n_vertices_global();
  out.n_cells = space.n_cells_global();
  out.nodes = space.canonical_coords();
  out.cells = space.canonical_cells();
  out.nodes_per_cell = int(out.cells.size() / std::size_t(out.n_cells));
}

}  // namespace

SolvedSetting solve_setting(const factory::ShapeSample& shape, const config::DatasetConfig& cfg,
                            const std::vector<factory::LoadCase>& cases, const Setting& s, int repeats,
                            double repeat_above, const std::string& prefix, bool verbose, const AfterLoad& after_load) {
  SolvedSetting out;
  reset_peak_resident();
  out.rss_before_mib = resident_mib();
  PetscOptionList petsc = s.petsc;
  try {
    const double t0 = core::now_seconds();
    physics::SpaceOptions so;
    so.degree = s.degree;
    so.quadrature_degree = s.quadrature;
    auto sp = factory::make_shape_problem(PETSC_COMM_SELF, cfg, shape, cases[0], so);
    physics::Problem& problem = *sp.problem;
    out.linear_solver = set_petsc_options(problem, s, prefix, petsc);
    solver::NonlinearSolver nl(problem, s.opt, prefix);
    out.seconds_setup = core::now_seconds() - t0;
    record_space(problem, out);
    core::VecH du = problem.create_vector();
    Solving w{shape, cfg, s, sp, nl, du};
    for (auto lc : cases) {
      rotate_load(lc, s.load_rotation);
      LoadOutcome lo = solve_load(w, lc, repeats, repeat_above);
      if (verbose)
        std::cerr << fmt::format("[study]   {} load {}/{}: {} ({} Newton its, {} solves), {:.2f} s x {}\n", s.name,
                                 out.loads.size() + 1, cases.size(), lo.converged ? "ok" : "FAILED: " + lo.reason,
                                 lo.newton, lo.solves, lo.seconds, lo.seconds_all.size());
      gather_displacement(w, lo);
      if (lo.converged && after_load) after_load(out.loads.size(), nl, problem);
      out.loads.push_back(std::move(lo));
    }
  } catch (const std::exception& e) {
    out.error = e.what();
  }
  for (const auto& [k, v] : petsc) HS_PETSC(PetscOptionsClearValue(nullptr, ("-" + prefix + k).c_str()));
  out.peak_rss_mib = peak_resident_mib();
  return out;
}

}  // namespace hypershape::study::accuracy
