#include "hypershape/study/bench_solver.hpp"

#include <petscksp.h>
#include <petscmat.h>
#include <petscsnes.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>

#include "hypershape/core/error.hpp"
#include "hypershape/core/petsc_handle.hpp"
#include "hypershape/mesh/gmsh_mesher.hpp"
#include "hypershape/physics/problem.hpp"
#include "hypershape/physics/registry.hpp"
#include "hypershape/solver/nonlinear.hpp"
#include "hypershape/study/machine.hpp"
#include "hypershape/study/output.hpp"
#include "hypershape/study/stats.hpp"
#include "hypershape/study/timing.hpp"

namespace hypershape::study {
namespace {

using json = nlohmann::json;

struct CaseSpec {
  int dim;
  int degree;
  double h;
};

/// Everything measured for one case: timings per repeat plus counts from each repeat.
struct CaseRecord {
  CaseSpec spec{};
  std::map<std::string, std::vector<double>> samples;  ///< seconds, one per repeat
  std::map<std::string, std::vector<double>> values;   ///< counts and checks, one per repeat
  std::vector<std::string> notes;
  std::string linear_solver;  ///< "pc_type/solver_type" of the SNES's KSP
  std::string error;

  void time(const std::string& k, double s) { samples[k].push_back(s); }
  void value(const std::string& k, double v) { values[k].push_back(v); }
};

double med(const CaseRecord& c, const std::string& k) {
  auto it = c.samples.find(k);
  return it == c.samples.end() ? NAN : median(it->second);
}
double last(const CaseRecord& c, const std::string& k) {
  auto it = c.values.find(k);
  return it == c.values.end() || it->second.empty() ? NAN : it->second.back();
}
bool varies(const CaseRecord& c, const std::string& k) {
  auto it = c.values.find(k);
  if (it == c.values.end() || it->second.empty()) return false;
  auto [lo, hi] = std::minmax_element(it->second.begin(), it->second.end());
  return *lo != *hi;
}

std::string fmt_ratio(double r) { return std::isfinite(r) ? fmt::format("{:.1f}x", r) : "-"; }

/// Relative difference ||a - b|| / ||a|| of two vectors.
double rel_diff(Vec a, Vec b) {
  core::VecH d;
  HS_PETSC(VecDuplicate(a, d.out()));
  HS_PETSC(VecWAXPY(d, -1.0, b, a));
  PetscReal nd, na;
  HS_PETSC(VecNorm(d, NORM_2, &nd));
  HS_PETSC(VecNorm(a, NORM_2, &na));
  return na > 0 ? nd / na : nd;
}

/// One repeat's problem, solver and the SNES's linear solver.
struct Bench {
  MPI_Comm comm = PETSC_COMM_WORLD;
  std::unique_ptr<physics::Problem> problem;
  std::unique_ptr<solver::NonlinearSolver> solver;
  Mat J = nullptr;
  KSP ksp = nullptr;
  PC pc = nullptr;
  bool mumps = false;
};

/// Mesh (rank 0; the Problem distributes it) and set-up (Problem + NonlinearSolver), timed.
void build(const CaseSpec& cs, Bench& b, CaseRecord& rec) {
  const int dim = cs.dim;
  const bool root = core::rank(b.comm) == 0;
  std::vector<double> p_d(dim, 0.0), p_n(dim, 0.0), dir(dim, 0.0);
  p_d[0] = 1.0;
  p_n[0] = -1.0;
  dir[1] = 1.0;
  mesh::MeshData mesh;
  {
    LogStage st("bench: mesh");
    mesh::ClampRegion clamp{{1.0, 0.0, 0.0}, 0.5};
    mesh::MeshOptions mo;
    mo.h = cs.h;
    mo.clamp_size = cs.h / 4;
    rec.time("mesh", timed(b.comm, [&] {
               if (root) mesh = dim == 2 ? mesh::mesh_disk(mo, clamp) : mesh::mesh_ball(mo, clamp);
             }));
  }
  LogStage st("bench: set-up");
  rec.time("setup", timed(b.comm, [&] {
             std::vector<physics::EffectPtr> effects;
             effects.push_back(physics::make_neo_hookean(500.0, 0.49));
             effects.push_back(physics::make_dirichlet_patch(p_d, 0.5));
             effects.push_back(physics::make_gaussian_traction(p_n, dir, 0.2));
             physics::SpaceOptions so;
             so.degree = cs.degree;
             b.problem = std::make_unique<physics::Problem>(b.comm, mesh, std::move(effects), so);
             b.solver = std::make_unique<solver::NonlinearSolver>(*b.problem);
           }));
}

/// Sizes, then the first (symbolic + numeric) factorisation of the tangent at u = 0 on the
/// SNES's own KSP and a repeat; records which linear solver that is.
void factorise_at_rest(Bench& b, CaseRecord& rec) {
  const auto& space = b.problem->space();
  rec.value("vertices", double(space.n_vertices_global()));
  rec.value("cells", double(space.n_cells_global()));
  rec.value("dofs", double(space.n_dofs_global()));
  PetscInt n_global;
  HS_PETSC(VecGetSize(b.problem->load(), &n_global));
  rec.value("free_dofs", double(n_global));
  b.J = b.solver->jacobian_matrix();
  HS_PETSC(SNESGetKSP(b.solver->snes(), &b.ksp));
  HS_PETSC(KSPGetPC(b.ksp, &b.pc));
  MatInfo info;
  HS_PETSC(MatGetInfo(b.J, MAT_GLOBAL_SUM, &info));
  rec.value("matrix_nonzeros", info.nz_allocated);
  b.solver->reset();
  Vec u = b.solver->solution();
  {
    LogStage st("bench: factorisation");
    if (!b.problem->jacobian(u, b.J)) throw std::runtime_error("tangent at u = 0 reports det F <= 0");
    HS_PETSC(KSPSetOperators(b.ksp, b.J, b.J));
    rec.time("factor_first", timed(b.comm, [&] { HS_PETSC(PCSetUp(b.pc)); }));
    if (!b.problem->jacobian(u, b.J)) throw std::runtime_error("tangent at u = 0 reports det F <= 0");
    rec.time("factor_repeat_u0", timed(b.comm, [&] { HS_PETSC(PCSetUp(b.pc)); }));
  }
  PCType pc_type;
  HS_PETSC(PCGetType(b.pc, &pc_type));
  MatSolverType solver_type = nullptr;
  PetscBool is_factor = PETSC_FALSE;
  HS_PETSC(PetscObjectTypeCompareAny((PetscObject)b.pc, &is_factor, PCLU, PCCHOLESKY, ""));
  if (is_factor) HS_PETSC(PCFactorGetMatSolverType(b.pc, &solver_type));
  b.mumps = solver_type && std::string(solver_type) == MATSOLVERMUMPS;
  rec.linear_solver = fmt::format("{}/{}", pc_type, solver_type ? solver_type : "-");
}

/// The target solve of `target` from the current state, timed as `key`; records its counts
/// under `prefix`_*. Returns the result.
solver::TargetResult target_solve(Bench& b, double target, bool from_rest, const char* stage,
                                  const std::string& key, const std::string& prefix, CaseRecord& rec) {
  solver::TargetResult tr;
  {
    LogStage st(stage);
    if (from_rest) b.solver->reset();
    rec.time(key, timed(b.comm, [&] { tr = b.solver->solve_for_target(target); }));
  }
  rec.value(prefix + "_converged", tr.converged ? 1 : 0);
  return tr;
}

/// What every residual/energy/Jacobian call pays before its cell loop (Problem::to_local).
void time_to_local(Bench& b, Vec ustar, CaseRecord& rec) {
  DM dm = b.problem->dm();
  Vec ul;
  HS_PETSC(DMGetLocalVector(dm, &ul));
  rec.time("global_to_local", timed(b.comm, [&] { HS_PETSC(DMGlobalToLocal(dm, ustar, INSERT_VALUES, ul)); }));
  rec.time("insert_bc", timed(b.comm, [&] {
             HS_PETSC(DMPlexInsertBoundaryValues(dm, PETSC_TRUE, ul, 0.0, nullptr, nullptr, nullptr));
           }));
  // The essential conditions are homogeneous, so zeroing the local vector before the
  // scatter gives the same local state; measured here as the candidate replacement.
  Vec uz;
  HS_PETSC(DMGetLocalVector(dm, &uz));
  rec.time("zero_global_to_local", timed(b.comm, [&] {
             HS_PETSC(VecZeroEntries(uz));
             HS_PETSC(DMGlobalToLocal(dm, ustar, INSERT_VALUES, uz));
           }));
  HS_PETSC(VecAXPY(uz, -1.0, ul));
  PetscReal dmax;
  HS_PETSC(VecNorm(uz, NORM_INFINITY, &dmax));
  rec.value("zero_global_to_local_max_diff", dmax);
  HS_PETSC(DMRestoreLocalVector(dm, &uz));
  HS_PETSC(DMRestoreLocalVector(dm, &ul));
}

/// Energy, residual and Jacobian at u*, hand-written and pointwise (PetscDS), and how far
/// the two paths differ (load factor 0 for the residual).
void time_assembly(Bench& b, Vec ustar, double alpha, CaseRecord& rec) {
  physics::Problem& problem = *b.problem;
  core::VecH r = problem.create_vector(), r0 = problem.create_vector(), rpw = problem.create_vector();
  double e = 0;
  rec.time("energy", timed(b.comm, [&] { problem.energy(ustar, alpha, e); }));
  rec.time("residual", timed(b.comm, [&] { problem.residual(ustar, alpha, r); }));
  rec.time("jacobian", timed(b.comm, [&] { problem.jacobian(ustar, b.J); }));
  rec.time("residual_pointwise", timed(b.comm, [&] { problem.residual_pointwise(ustar, rpw); }));
  core::MatH jpw = problem.create_matrix();
  rec.time("jacobian_pointwise", timed(b.comm, [&] { problem.jacobian_pointwise(ustar, jpw); }));
  problem.residual(ustar, 0.0, r0);
  rec.value("residual_pointwise_rel_diff", rel_diff(r0, rpw));
  PetscReal nj, nd;
  HS_PETSC(MatNorm(b.J, NORM_FROBENIUS, &nj));
  HS_PETSC(MatAXPY(jpw, -1.0, b.J, DIFFERENT_NONZERO_PATTERN));
  HS_PETSC(MatNorm(jpw, NORM_FROBENIUS, &nd));
  rec.value("jacobian_pointwise_rel_diff", nj > 0 ? nd / nj : nd);
}

/// A numeric factorisation of J (holding the Jacobian at u*) and one triangular solve; with
/// MUMPS, the size and flops of the factors.
void time_factor_solve(Bench& b, CaseRecord& rec) {
  core::VecH du = b.problem->create_vector();
  HS_PETSC(KSPSetOperators(b.ksp, b.J, b.J));
  rec.time("factor_repeat", timed(b.comm, [&] { HS_PETSC(PCSetUp(b.pc)); }));
  rec.time("triangular_solve", timed(b.comm, [&] { HS_PETSC(KSPSolve(b.ksp, b.problem->load(), du)); }));
  if (!b.mumps) return;
  Mat F;
  HS_PETSC(PCFactorGetMatrix(b.pc, &F));
  PetscInt entries = 0;
  PetscReal flops = 0;
  HS_PETSC(MatMumpsGetInfog(F, 29, &entries));  // entries in the factors (after numeric)
  HS_PETSC(MatMumpsGetRinfog(F, 3, &flops));    // flops of the elimination
  rec.value("factor_entries", double(entries));
  rec.value("factor_flops", double(flops));
}

/// A full solve at `alpha` from u = 0, then a second load case from the converged state.
void solve_again(const SolverBenchOptions& set, Bench& b, double alpha, CaseRecord& rec) {
  solver::SolveResult sr;
  {
    LogStage st("bench: full solve");
    b.solver->reset();
    rec.time("full_solve", timed(b.comm, [&] { sr = b.solver->solve(alpha); }));
  }
  rec.value("full_converged", sr.converged ? 1 : 0);
  rec.value("full_newton", sr.newton_iterations);
  rec.value("full_increments", sr.increments);
  rec.value("full_failed_increments", sr.failed_increments);
  rec.value("full_max_u", sr.max_displacement);
  rec.value("full_residual_norm", sr.residual_norm);
  if (!sr.converged) rec.notes.push_back("full solve at alpha failed: " + sr.reason);

  const auto tr2 = target_solve(b, set.second_target, false, "bench: second load case", "second_load", "second", rec);
  rec.value("second_alpha", tr2.alpha);
  rec.value("second_solves", tr2.solves);
  rec.value("second_newton", tr2.newton_iterations);
  rec.value("second_failed_increments", tr2.failed_increments);
  if (!tr2.converged) rec.notes.push_back("second load case failed: " + tr2.reason);
}

/// One repeat of one case; fills `rec`. Throws on set-up failures (caught per case).
void run_once(const SolverBenchOptions& set, const CaseSpec& cs, CaseRecord& rec) {
  Bench b;
  build(cs, b, rec);
  factorise_at_rest(b, rec);
  const auto tr = target_solve(b, set.target, true, "bench: alpha search", "target_solve", "target", rec);
  rec.value("alpha", tr.alpha);
  rec.value("target_max_u", tr.max_displacement);
  rec.value("target_solves", tr.solves);
  rec.value("target_newton", tr.newton_iterations);
  rec.value("target_failed_increments", tr.failed_increments);
  if (!tr.converged) {
    rec.notes.push_back("alpha search failed: " + tr.reason);
    return;
  }
  core::VecH ustar = b.problem->create_vector();
  HS_PETSC(VecCopy(b.solver->solution(), ustar));
  rec.value("min_det_f", b.problem->min_det_f(ustar));
  {
    LogStage st("bench: kernels");
    time_to_local(b, ustar, rec);
    time_assembly(b, ustar, tr.alpha, rec);
    time_factor_solve(b, rec);
  }
  solve_again(set, b, tr.alpha, rec);
}

/// Derived quantities from the medians.
json derived(const CaseRecord& c) {
  json d;
  const double n = last(c, "full_newton");
  const double kern = n * (med(c, "jacobian") + med(c, "factor_repeat") + med(c, "triangular_solve")) +
                      (n + 1) * med(c, "residual");
  d["kernel_sum_full_solve"] = kern;
  d["full_solve_overhead"] = med(c, "full_solve") / kern;
  d["residual_pointwise_speedup"] = med(c, "residual_pointwise") / med(c, "residual");
  d["jacobian_pointwise_speedup"] = med(c, "jacobian_pointwise") / med(c, "jacobian");
  d["factor_symbolic_estimate"] = med(c, "factor_first") - med(c, "factor_repeat_u0");
  for (auto& [k, v] : d.items())
    if (!std::isfinite(v.get<double>())) v = nullptr;
  return d;
}

json to_json(const CaseRecord& c) {
  json j;
  j["dim"] = c.spec.dim;
  j["degree"] = c.spec.degree;
  j["h"] = c.spec.h;
  j["clamp_size"] = c.spec.h / 4;
  json med_j, samples_j, values_j;
  for (auto& [k, v] : c.samples) {
    med_j[k] = number_or_null(median(v));
    samples_j[k] = numbers_or_null(v);
  }
  for (auto& [k, v] : c.values) {
    values_j[k] = number_or_null(v.back());
    if (varies(c, k)) values_j[k + "_per_repeat"] = numbers_or_null(v);
  }
  j["median_seconds"] = med_j;
  j["samples_seconds"] = samples_j;
  j["values"] = values_j;
  j["derived"] = derived(c);
  j["linear_solver"] = c.linear_solver;
  j["notes"] = c.notes;
  j["error"] = c.error.empty() ? json(nullptr) : json(c.error);
  return j;
}

/// A derived quantity, NaN where null.
double derived_value(const json& d, const char* k) { return d[k].is_null() ? NAN : d[k].get<double>(); }

void print_sizes_table(std::ostream& os, const std::vector<CaseRecord>& recs) {
  os << "\nSizes, Newton iterations and solve times (median over repeats)\n";
  os << fmt::format("{:>3} {:>2} {:>6} {:>7} {:>8} {:>8} {:>8} | {:>5} {:>6} {:>10} {:>8} | {:>9} {:>9} | "
                    "{:>13} {:>9} | {:>9} {:>8}\n",
                    "dim", "P", "h", "verts", "DoFs", "mesh", "set-up", "its", "incr", "alpha", "full", "kernels",
                    "overhead", "alpha search", "(solv/its)", "2nd load", "(its)");
  for (const auto& c : recs) {
    const auto& s = c.spec;
    if (!c.error.empty()) {
      os << fmt::format("{:>3} {:>2} {:>6} ERROR: {}\n", s.dim, s.degree, s.h, c.error);
      continue;
    }
    const json d = derived(c);
    os << fmt::format(
        "{:>3} {:>2} {:>6} {:>7} {:>8} {:>8} {:>8} | {:>5} {:>6} {:>10.4g} {:>8} | {:>9} {:>9} | "
        "{:>13} {:>9} | {:>9} {:>8}\n",
        s.dim, s.degree, s.h, format_count(last(c, "vertices")), format_count(last(c, "free_dofs")),
        format_seconds(med(c, "mesh")), format_seconds(med(c, "setup")), format_count(last(c, "full_newton")),
        format_count(last(c, "full_increments")) + "/" + format_count(last(c, "full_failed_increments")),
        last(c, "alpha"), format_seconds(med(c, "full_solve")),
        format_seconds(derived_value(d, "kernel_sum_full_solve")), fmt_ratio(derived_value(d, "full_solve_overhead")),
        format_seconds(med(c, "target_solve")),
        format_count(last(c, "target_solves")) + "/" + format_count(last(c, "target_newton")),
        format_seconds(med(c, "second_load")),
        format_count(last(c, "second_solves")) + "/" + format_count(last(c, "second_newton")));
  }
}

void print_kernels_table(std::ostream& os, const std::vector<CaseRecord>& recs) {
  os << "\nKernels at the converged state (median over repeats)\n";
  os << fmt::format("{:>3} {:>2} {:>6} | {:>8} {:>8} {:>8} | {:>8} {:>7} | {:>8} {:>7} | {:>9} "
                    "{:>9} {:>9} {:>9} | {:>8}\n",
                    "dim", "P", "h", "energy", "residual", "Jacobian", "res(pw)", "ratio", "Jac(pw)", "ratio",
                    "fact 1st", "fact rep", "fact u=0", "tri solve", "to_local");
  for (const auto& c : recs) {
    if (!c.error.empty()) continue;
    const auto& s = c.spec;
    const json d = derived(c);
    os << fmt::format(
        "{:>3} {:>2} {:>6} | {:>8} {:>8} {:>8} | {:>8} {:>7} | {:>8} {:>7} | {:>9} {:>9} {:>9} "
        "{:>9} | {:>8}\n",
        s.dim, s.degree, s.h, format_seconds(med(c, "energy")), format_seconds(med(c, "residual")),
        format_seconds(med(c, "jacobian")), format_seconds(med(c, "residual_pointwise")),
        fmt_ratio(derived_value(d, "residual_pointwise_speedup")), format_seconds(med(c, "jacobian_pointwise")),
        fmt_ratio(derived_value(d, "jacobian_pointwise_speedup")), format_seconds(med(c, "factor_first")),
        format_seconds(med(c, "factor_repeat")), format_seconds(med(c, "factor_repeat_u0")),
        format_seconds(med(c, "triangular_solve")), format_seconds(med(c, "global_to_local") + med(c, "insert_bc")));
  }
}

void print_tables(std::ostream& os, const std::vector<CaseRecord>& recs) {
  print_sizes_table(os, recs);
  print_kernels_table(os, recs);
  os << "\nDoFs: free (unconstrained) dofs.  its, incr: Newton iterations and continuation "
        "increments (successful/failed) of full.\n"
        "Counts and alpha are from the last repeat; every sample is in the JSON.\n";
  os << "full = reset(); solve(alpha).  kernels = its x (Jacobian + fact rep + tri solve) + "
        "(its + 1) x residual;\noverhead = full / kernels.  alpha search = reset(); "
        "solve_for_target(0.3) (symbolic analysis already done).\n2nd load = solve_for_target(0.15) "
        "from the converged state.  ratio = pointwise / hand-written.\n"
        "to_local = DMGlobalToLocal + DMPlexInsertBoundaryValues, paid by every energy, residual "
        "and Jacobian call.\n";
  bool any_note = false;
  for (const auto& c : recs) {
    const auto& lines = c.notes;
    if (lines.empty()) continue;
    if (!any_note) os << "\nNotes\n";
    any_note = true;
    for (const auto& n : lines) os << fmt::format("  {}D P{} h={}: {}\n", c.spec.dim, c.spec.degree, c.spec.h, n);
  }
}

/// Checks that turn into notes (anomalies worth a look).
void add_checks(CaseRecord& c) {
  for (const char* k : {"vertices", "free_dofs", "alpha", "full_newton", "target_newton", "second_newton"})
    if (varies(c, k)) {
      const auto& v = c.values.at(k);
      auto [lo, hi] = std::minmax_element(v.begin(), v.end());
      c.notes.push_back(fmt::format("{} differs between repeats: {:.6g} .. {:.6g}", k, *lo, *hi));
    }
  const double rd = last(c, "residual_pointwise_rel_diff"), jd = last(c, "jacobian_pointwise_rel_diff");
  if (std::isfinite(rd) && rd > 1e-8)
    c.notes.push_back(fmt::format("pointwise residual differs from hand-written: rel {:.2e}", rd));
  if (std::isfinite(jd) && jd > 1e-8)
    c.notes.push_back(fmt::format("pointwise Jacobian differs from hand-written: rel {:.2e}", jd));
  const double md = last(c, "min_det_f");
  if (std::isfinite(md) && md < 0.2) c.notes.push_back(fmt::format("min det F at max|u| = target: {:.3f}", md));
  const double fn = last(c, "full_newton");
  if (std::isfinite(fn) && fn > 15)
    c.notes.push_back(fmt::format("full solve took {} Newton iterations ({} increments, {} failed)", fn,
                                  last(c, "full_increments"), last(c, "full_failed_increments")));
  else if (last(c, "full_failed_increments") > 0)
    c.notes.push_back(fmt::format("full solve needed continuation: {} increments, {} failed",
                                  last(c, "full_increments"), last(c, "full_failed_increments")));
}

std::vector<CaseSpec> make_cases(const SolverBenchOptions& set) {
  std::vector<CaseSpec> cases;
  for (int dim : set.dims) {
    auto sizes = dim == 2 ? set.sizes2d : set.sizes3d;
    std::sort(sizes.begin(), sizes.end(), std::greater<>());
    if (set.quick && sizes.size() > 2) sizes.resize(2);
    for (int p : set.degrees)
      for (double h : sizes) cases.push_back({dim, p, h});
  }
  return cases;
}

json start_output(const SolverBenchOptions& set) {
  json out;
  out["benchmark"] = "bench_solver";
  out["machine"] = machine_note();
  out["machine"]["mpi_ranks"] = core::size(PETSC_COMM_WORLD);
  out["settings"] = {{"repeats", set.repeats},
                     {"quick", set.quick},
                     {"target", set.target},
                     {"second_target", set.second_target},
                     {"scene",
                      {{"neo_hookean", {{"E", 500.0}, {"nu", 0.49}}},
                       {"dirichlet_patch", {{"center_x", 1.0}, {"radius", 0.5}}},
                       {"gaussian_traction", {{"center_x", -1.0}, {"direction", "e_y"}, {"gamma", 0.2}}},
                       {"mesh", {{"clamp_size", "h/4"}}}}}};
  out["settings"]["petsc_args"] = set.petsc_args;
  out["cases"] = json::array();
  return out;
}

/// Every repeat of one case, with a progress line per repeat (rank 0), then the checks.
CaseRecord run_case(const SolverBenchOptions& set, const CaseSpec& cs) {
  CaseRecord rec;
  rec.spec = cs;
  const double t_case = core::now_seconds();
  for (int r = 0; r < set.repeats; ++r) {
    try {
      run_once(set, cs, rec);
    } catch (const std::exception& e) {
      rec.error = e.what();
      break;
    }
    if (core::rank(PETSC_COMM_WORLD) == 0)
      std::cerr << fmt::format("[bench] {}D P{} h={} repeat {}/{}: {} DoFs, alpha {:.5g}, {} its, {:.1f}s so far\n",
                               cs.dim, cs.degree, cs.h, r + 1, set.repeats, format_count(last(rec, "free_dofs")),
                               last(rec, "alpha"), format_count(last(rec, "full_newton")),
                               core::now_seconds() - t_case);
  }
  add_checks(rec);
  return rec;
}

}  // namespace

void run_solver_bench(const SolverBenchOptions& set, std::ostream& table) {
  const bool root = core::rank(PETSC_COMM_WORLD) == 0;
  json out = start_output(set);
  std::vector<CaseRecord> recs;
  const double t_all = core::now_seconds();
  for (const auto& cs : make_cases(set)) {
    recs.push_back(run_case(set, cs));
    out["cases"].push_back(to_json(recs.back()));
    out["total_seconds"] = core::now_seconds() - t_all;
    if (root && !set.json_path.empty()) write_json_atomic(set.json_path, out, "--json");
  }
  if (!root) return;
  print_tables(table, recs);
  table << fmt::format("\ntotal {:.1f}s on {} ({} cores, {}), {} repeats\n", core::now_seconds() - t_all,
                       out["machine"]["hostname"].get<std::string>(), out["machine"]["nproc"].get<long>(),
                       out["machine"]["petsc_version"].get<std::string>(), set.repeats);
  if (set.json_path.empty()) table << out.dump(2) << "\n";
}

}  // namespace hypershape::study
