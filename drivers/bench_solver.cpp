/// bench_solver: where the time of one Neo-Hookean load case goes.
///
/// Scene (the disk/ball problem of the dataset): unit disk (2D) or unit ball (3D),
///   neo_hookean E = 500, nu = 0.49;
///   dirichlet_patch center p_D = (1, 0[, 0]), radius 0.5 (the mesh has vertices on its ends);
///   gaussian_traction center p_N = (-1, 0[, 0]), direction (0, 1[, 0]), gamma 0.2, scaled by
///   alpha, which the alpha search tunes so that max|u| = 0.3.
/// Meshes: mesh::mesh_disk / mesh_ball with ClampRegion{p_D, 0.5}, MeshOptions{h, h / 4}.
///
/// For each (dim, degree, h) and each repeat, in this order (each step timed):
///   mesh; set-up (Problem + NonlinearSolver); first numeric+symbolic factorisation of the
///   tangent at u = 0 on the SNES's own KSP (so the solves below reuse that analysis), then a
///   repeat at u = 0; alpha search from u = 0 (solve_for_target(0.3)); at the converged state
///   u*: energy, residual, Jacobian, the same two through PETSc's pointwise (PetscDS) path,
///   one numeric factorisation and one triangular solve; a full solve at that alpha from u = 0;
///   a second load case from u* (solve_for_target(0.15)).
/// Reported: the median over repeats (all samples go to the JSON).
///
/// Sample runs (OPENBLAS_NUM_THREADS=1):
///   bench_solver --quick --json bench_quick.json
///   bench_solver --dims 2 --json bench_2d.json
///   bench_solver --dims 3 --degrees 1 --sizes3d 0.3 --repeats 1 -- -log_view
/// Arguments after "--" go to PETSc (solver options, -log_view).
#include <petscksp.h>
#include <petscmat.h>
#include <petscsnes.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "driver_support.hpp"
#include "hypershape/core/error.hpp"
#include "hypershape/core/petsc_handle.hpp"
#include "hypershape/core/timer.hpp"
#include "hypershape/mesh/gmsh_mesher.hpp"
#include "hypershape/physics/problem.hpp"
#include "hypershape/physics/registry.hpp"
#include "hypershape/solver/nonlinear.hpp"

namespace hs = hypershape;
using json = nlohmann::json;

namespace {

constexpr const char* help_text =
    "bench_solver: per-phase timings of the disk/ball Neo-Hookean solves (see the source "
    "header).\nOptions after \"--\" go to PETSc.\n";

struct Settings {
  std::vector<int> dims{2, 3};
  std::vector<int> degrees{1, 2};
  std::vector<double> sizes2d{0.1, 0.05, 0.025};
  std::vector<double> sizes3d{0.3, 0.2, 0.15};
  int repeats = 3;
  bool quick = false;
  double target = 0.3;
  double second_target = 0.15;
  std::string json_path;
};

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

double median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

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

/// Wall time of `f` in seconds, with every rank lined up before and after (collective).
template <class F>
double timed(MPI_Comm comm, F&& f) {
  MPI_Barrier(comm);
  const double t0 = hs::core::now_seconds();
  f();
  MPI_Barrier(comm);
  return hs::core::now_seconds() - t0;
}

/// PETSc log stage pushed for a scope, so that -log_view splits the run the same way.
class Stage {
 public:
  explicit Stage(const char* name) {
    static std::map<std::string, PetscLogStage> stages;
    auto it = stages.find(name);
    if (it == stages.end()) {
      PetscLogStage s;
      HS_PETSC(PetscLogStageRegister(name, &s));
      it = stages.emplace(name, s).first;
    }
    HS_PETSC(PetscLogStagePush(it->second));
  }
  ~Stage() { PetscLogStagePop(); }
  Stage(const Stage&) = delete;
  Stage& operator=(const Stage&) = delete;
};

std::string fmt_time(double s) {
  if (!std::isfinite(s)) return "-";
  if (s < 1e-3) return fmt::format("{:.0f}us", s * 1e6);
  if (s < 1.0) return fmt::format("{:.1f}ms", s * 1e3);
  if (s < 100.0) return fmt::format("{:.2f}s", s);
  return fmt::format("{:.0f}s", s);
}
std::string fmt_ratio(double r) { return std::isfinite(r) ? fmt::format("{:.1f}x", r) : "-"; }
std::string fmt_count(double v) {
  return std::isfinite(v) ? fmt::format("{}", static_cast<long long>(std::llround(v))) : "-";
}

/// Relative difference ||a - b|| / ||a|| of two vectors.
double rel_diff(Vec a, Vec b) {
  hs::core::VecH d;
  HS_PETSC(VecDuplicate(a, d.out()));
  HS_PETSC(VecWAXPY(d, -1.0, b, a));
  PetscReal nd, na;
  HS_PETSC(VecNorm(d, NORM_2, &nd));
  HS_PETSC(VecNorm(a, NORM_2, &na));
  return na > 0 ? nd / na : nd;
}

/// One repeat of one case; fills `rec`. Throws on set-up failures (caught per case).
void run_once(const Settings& set, const CaseSpec& cs, CaseRecord& rec) {
  MPI_Comm comm = PETSC_COMM_WORLD;
  const int dim = cs.dim;
  const bool root = hs::core::rank(comm) == 0;
  std::vector<double> p_d(dim, 0.0), p_n(dim, 0.0), dir(dim, 0.0);
  p_d[0] = 1.0;
  p_n[0] = -1.0;
  dir[1] = 1.0;

  // ---- mesh (rank 0; the Problem distributes it) ----
  hs::mesh::MeshData mesh;
  {
    Stage st("bench: mesh");
    hs::mesh::ClampRegion clamp{{1.0, 0.0, 0.0}, 0.5};
    hs::mesh::MeshOptions mo;
    mo.h = cs.h;
    mo.clamp_size = cs.h / 4;
    rec.time("mesh", timed(comm, [&] {
               if (root) mesh = dim == 2 ? hs::mesh::mesh_disk(mo, clamp)
                                         : hs::mesh::mesh_ball(mo, clamp);
             }));
  }

  // ---- set-up: Problem + NonlinearSolver ----
  std::unique_ptr<hs::physics::Problem> problem;
  std::unique_ptr<hs::solver::NonlinearSolver> solver;
  {
    Stage st("bench: set-up");
    rec.time("setup", timed(comm, [&] {
               std::vector<hs::physics::EffectPtr> effects;
               effects.push_back(hs::physics::make_neo_hookean(500.0, 0.49));
               effects.push_back(hs::physics::make_dirichlet_patch(p_d, 0.5));
               effects.push_back(hs::physics::make_gaussian_traction(p_n, dir, 0.2));
               hs::physics::SpaceOptions so;
               so.degree = cs.degree;
               problem = std::make_unique<hs::physics::Problem>(comm, mesh, std::move(effects), so);
               solver = std::make_unique<hs::solver::NonlinearSolver>(*problem);
             }));
  }
  const auto& space = problem->space();
  rec.value("vertices", double(space.n_vertices_global()));
  rec.value("cells", double(space.n_cells_global()));
  rec.value("dofs", double(space.n_dofs_global()));
  PetscInt n_global;
  HS_PETSC(VecGetSize(problem->load(), &n_global));
  rec.value("free_dofs", double(n_global));

  Mat J = solver->jacobian_matrix();
  KSP ksp;
  PC pc;
  HS_PETSC(SNESGetKSP(solver->snes(), &ksp));
  HS_PETSC(KSPGetPC(ksp, &pc));
  {
    MatInfo info;
    HS_PETSC(MatGetInfo(J, MAT_GLOBAL_SUM, &info));
    rec.value("matrix_nonzeros", info.nz_allocated);
  }

  // ---- first factorisation (symbolic + numeric) on the SNES's KSP, at u = 0 ----
  solver->reset();
  Vec u = solver->solution();
  {
    Stage st("bench: factorisation");
    if (!problem->jacobian(u, J)) throw std::runtime_error("tangent at u = 0 reports det F <= 0");
    HS_PETSC(KSPSetOperators(ksp, J, J));
    rec.time("factor_first", timed(comm, [&] { HS_PETSC(PCSetUp(pc)); }));
    if (!problem->jacobian(u, J)) throw std::runtime_error("tangent at u = 0 reports det F <= 0");
    rec.time("factor_repeat_u0", timed(comm, [&] { HS_PETSC(PCSetUp(pc)); }));
  }
  PCType pc_type;
  HS_PETSC(PCGetType(pc, &pc_type));
  MatSolverType solver_type = nullptr;
  PetscBool is_factor = PETSC_FALSE;
  HS_PETSC(PetscObjectTypeCompareAny((PetscObject)pc, &is_factor, PCLU, PCCHOLESKY, ""));
  if (is_factor) HS_PETSC(PCFactorGetMatSolverType(pc, &solver_type));
  const bool mumps = solver_type && std::string(solver_type) == MATSOLVERMUMPS;
  rec.linear_solver = fmt::format("{}/{}", pc_type, solver_type ? solver_type : "-");

  // ---- alpha search from u = 0 ----
  hs::solver::TargetResult tr;
  {
    Stage st("bench: alpha search");
    solver->reset();
    rec.time("target_solve", timed(comm, [&] { tr = solver->solve_for_target(set.target); }));
  }
  rec.value("target_converged", tr.converged ? 1 : 0);
  rec.value("alpha", tr.alpha);
  rec.value("target_max_u", tr.max_displacement);
  rec.value("target_solves", tr.solves);
  rec.value("target_newton", tr.newton_iterations);
  rec.value("target_failed_increments", tr.failed_increments);
  if (!tr.converged) {
    rec.notes.push_back("alpha search failed: " + tr.reason);
    return;
  }
  const double alpha = tr.alpha;

  // ---- kernels at the converged state u* ----
  hs::core::VecH ustar = problem->create_vector();
  HS_PETSC(VecCopy(solver->solution(), ustar));
  rec.value("min_det_f", problem->min_det_f(ustar));
  {
    Stage st("bench: kernels");
    hs::core::VecH r = problem->create_vector(), r0 = problem->create_vector(),
                   rpw = problem->create_vector(), du = problem->create_vector();
    // What every residual/energy/Jacobian call pays before its cell loop (Problem::to_local).
    {
      DM dm = problem->dm();
      Vec ul;
      HS_PETSC(DMGetLocalVector(dm, &ul));
      rec.time("global_to_local",
               timed(comm, [&] { HS_PETSC(DMGlobalToLocal(dm, ustar, INSERT_VALUES, ul)); }));
      rec.time("insert_bc", timed(comm, [&] {
                 HS_PETSC(DMPlexInsertBoundaryValues(dm, PETSC_TRUE, ul, 0.0, nullptr, nullptr,
                                                     nullptr));
               }));
      // The essential conditions are homogeneous, so zeroing the local vector before the
      // scatter gives the same local state; measured here as the candidate replacement.
      Vec uz;
      HS_PETSC(DMGetLocalVector(dm, &uz));
      rec.time("zero_global_to_local", timed(comm, [&] {
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
    double e = 0;
    rec.time("energy", timed(comm, [&] { problem->energy(ustar, alpha, e); }));
    rec.time("residual", timed(comm, [&] { problem->residual(ustar, alpha, r); }));
    rec.time("jacobian", timed(comm, [&] { problem->jacobian(ustar, J); }));
    rec.time("residual_pointwise", timed(comm, [&] { problem->residual_pointwise(ustar, rpw); }));
    hs::core::MatH jpw = problem->create_matrix();
    rec.time("jacobian_pointwise",
             timed(comm, [&] { problem->jacobian_pointwise(ustar, jpw); }));
    // The two paths must agree (load factor 0 for the residual).
    problem->residual(ustar, 0.0, r0);
    rec.value("residual_pointwise_rel_diff", rel_diff(r0, rpw));
    PetscReal nj, nd;
    HS_PETSC(MatNorm(J, NORM_FROBENIUS, &nj));
    HS_PETSC(MatAXPY(jpw, -1.0, J, DIFFERENT_NONZERO_PATTERN));
    HS_PETSC(MatNorm(jpw, NORM_FROBENIUS, &nd));
    rec.value("jacobian_pointwise_rel_diff", nj > 0 ? nd / nj : nd);

    // J holds new values (the Jacobian at u*): PCSetUp is a numeric factorisation only.
    HS_PETSC(KSPSetOperators(ksp, J, J));
    rec.time("factor_repeat", timed(comm, [&] { HS_PETSC(PCSetUp(pc)); }));
    rec.time("triangular_solve",
             timed(comm, [&] { HS_PETSC(KSPSolve(ksp, problem->load(), du)); }));
    if (mumps) {
      Mat F;
      HS_PETSC(PCFactorGetMatrix(pc, &F));
      PetscInt entries = 0;
      PetscReal flops = 0;
      HS_PETSC(MatMumpsGetInfog(F, 29, &entries));  // entries in the factors (after numeric)
      HS_PETSC(MatMumpsGetRinfog(F, 3, &flops));    // flops of the elimination
      rec.value("factor_entries", double(entries));
      rec.value("factor_flops", double(flops));
    }
  }

  // ---- full solve at the alpha found, from u = 0 ----
  hs::solver::SolveResult sr;
  {
    Stage st("bench: full solve");
    solver->reset();
    rec.time("full_solve", timed(comm, [&] { sr = solver->solve(alpha); }));
  }
  rec.value("full_converged", sr.converged ? 1 : 0);
  rec.value("full_newton", sr.newton_iterations);
  rec.value("full_increments", sr.increments);
  rec.value("full_failed_increments", sr.failed_increments);
  rec.value("full_max_u", sr.max_displacement);
  rec.value("full_residual_norm", sr.residual_norm);
  if (!sr.converged) rec.notes.push_back("full solve at alpha failed: " + sr.reason);

  // ---- second load case on the same problem, from the converged state ----
  hs::solver::TargetResult tr2;
  {
    Stage st("bench: second load case");
    rec.time("second_load", timed(comm, [&] { tr2 = solver->solve_for_target(set.second_target); }));
  }
  rec.value("second_converged", tr2.converged ? 1 : 0);
  rec.value("second_alpha", tr2.alpha);
  rec.value("second_solves", tr2.solves);
  rec.value("second_newton", tr2.newton_iterations);
  rec.value("second_failed_increments", tr2.failed_increments);
  if (!tr2.converged) rec.notes.push_back("second load case failed: " + tr2.reason);
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
  auto clean = [](double v) { return std::isfinite(v) ? json(v) : json(nullptr); };
  json med_j, samples_j, values_j;
  for (auto& [k, v] : c.samples) {
    med_j[k] = clean(median(v));
    json arr = json::array();
    for (double x : v) arr.push_back(clean(x));
    samples_j[k] = arr;
  }
  for (auto& [k, v] : c.values) {
    values_j[k] = clean(v.back());
    if (varies(c, k)) {
      json arr = json::array();
      for (double x : v) arr.push_back(clean(x));
      values_j[k + "_per_repeat"] = arr;
    }
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

json machine_note(MPI_Comm comm) {
  json m = hs::drivers::machine_note();
  m["mpi_ranks"] = hs::core::size(comm);
  return m;
}

void print_tables(std::ostream& os, const std::vector<CaseRecord>& recs) {
  os << "\nSizes, Newton iterations and solve times (median over repeats)\n";
  os << fmt::format("{:>3} {:>2} {:>6} {:>7} {:>8} {:>8} {:>8} | {:>5} {:>6} {:>10} {:>8} | {:>9} {:>9} | "
                    "{:>13} {:>9} | {:>9} {:>8}\n",
                    "dim", "P", "h", "verts", "DoFs", "mesh", "set-up", "its", "incr", "alpha",
                    "full", "kernels", "overhead", "alpha search", "(solv/its)", "2nd load",
                    "(its)");
  for (const auto& c : recs) {
    const auto& s = c.spec;
    if (!c.error.empty()) {
      os << fmt::format("{:>3} {:>2} {:>6} ERROR: {}\n", s.dim, s.degree, s.h, c.error);
      continue;
    }
    json d = derived(c);
    auto dv = [&](const char* k) { return d[k].is_null() ? NAN : d[k].get<double>(); };
    os << fmt::format(
        "{:>3} {:>2} {:>6} {:>7} {:>8} {:>8} {:>8} | {:>5} {:>6} {:>10.4g} {:>8} | {:>9} {:>9} | "
        "{:>13} {:>9} | {:>9} {:>8}\n",
        s.dim, s.degree, s.h, fmt_count(last(c, "vertices")), fmt_count(last(c, "free_dofs")),
        fmt_time(med(c, "mesh")), fmt_time(med(c, "setup")), fmt_count(last(c, "full_newton")),
        fmt_count(last(c, "full_increments")) + "/" + fmt_count(last(c, "full_failed_increments")),
        last(c, "alpha"), fmt_time(med(c, "full_solve")), fmt_time(dv("kernel_sum_full_solve")),
        fmt_ratio(dv("full_solve_overhead")), fmt_time(med(c, "target_solve")),
        fmt_count(last(c, "target_solves")) + "/" + fmt_count(last(c, "target_newton")),
        fmt_time(med(c, "second_load")),
        fmt_count(last(c, "second_solves")) + "/" + fmt_count(last(c, "second_newton")));
  }
  os << "\nKernels at the converged state (median over repeats)\n";
  os << fmt::format("{:>3} {:>2} {:>6} | {:>8} {:>8} {:>8} | {:>8} {:>7} | {:>8} {:>7} | {:>9} "
                    "{:>9} {:>9} {:>9} | {:>8}\n",
                    "dim", "P", "h", "energy", "residual", "Jacobian", "res(pw)", "ratio",
                    "Jac(pw)", "ratio", "fact 1st", "fact rep", "fact u=0", "tri solve", "to_local");
  for (const auto& c : recs) {
    if (!c.error.empty()) continue;
    const auto& s = c.spec;
    json d = derived(c);
    auto dv = [&](const char* k) { return d[k].is_null() ? NAN : d[k].get<double>(); };
    os << fmt::format(
        "{:>3} {:>2} {:>6} | {:>8} {:>8} {:>8} | {:>8} {:>7} | {:>8} {:>7} | {:>9} {:>9} {:>9} "
        "{:>9} | {:>8}\n",
        s.dim, s.degree, s.h, fmt_time(med(c, "energy")), fmt_time(med(c, "residual")),
        fmt_time(med(c, "jacobian")), fmt_time(med(c, "residual_pointwise")),
        fmt_ratio(dv("residual_pointwise_speedup")), fmt_time(med(c, "jacobian_pointwise")),
        fmt_ratio(dv("jacobian_pointwise_speedup")), fmt_time(med(c, "factor_first")),
        fmt_time(med(c, "factor_repeat")), fmt_time(med(c, "factor_repeat_u0")),
        fmt_time(med(c, "triangular_solve")),
        fmt_time(med(c, "global_to_local") + med(c, "insert_bc")));
  }
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
    for (const auto& n : lines)
      os << fmt::format("  {}D P{} h={}: {}\n", c.spec.dim, c.spec.degree, c.spec.h, n);
  }
}

/// Checks that turn into notes (anomalies worth a look).
void add_checks(CaseRecord& c) {
  for (const char* k : {"vertices", "free_dofs", "alpha", "full_newton", "target_newton",
                        "second_newton"})
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
  if (std::isfinite(md) && md < 0.2)
    c.notes.push_back(fmt::format("min det F at max|u| = target: {:.3f}", md));
  const double fn = last(c, "full_newton");
  if (std::isfinite(fn) && fn > 15)
    c.notes.push_back(fmt::format("full solve took {} Newton iterations ({} increments, {} failed)",
                                  fn, last(c, "full_increments"), last(c, "full_failed_increments")));
  else if (last(c, "full_failed_increments") > 0)
    c.notes.push_back(fmt::format("full solve needed continuation: {} increments, {} failed",
                                  last(c, "full_increments"), last(c, "full_failed_increments")));
}

}  // namespace

int main(int argc, char** argv) {
  auto [ours, petsc] = hs::drivers::split_at_dashes(argc, argv);
  Settings set;
  CLI::App app{"Per-phase timings of the disk/ball Neo-Hookean solves. Arguments after \"--\" go "
               "to PETSc (e.g. -- -log_view -pc_type lu)."};
  app.add_option("--dims", set.dims, "dimensions to run")->check(CLI::IsMember({2, 3}));
  app.add_option("--degrees", set.degrees, "polynomial degrees")->check(CLI::IsMember({1, 2}));
  app.add_option("--sizes2d", set.sizes2d, "mesh sizes h for the disk")
      ->check(CLI::PositiveNumber);
  app.add_option("--sizes3d", set.sizes3d, "mesh sizes h for the ball")
      ->check(CLI::PositiveNumber);
  app.add_option("--repeats", set.repeats, "repeats per case (median reported)")
      ->check(CLI::Range(1, 100));
  app.add_flag("--quick", set.quick, "only the two coarsest sizes of each dimension");
  app.add_option("--target", set.target, "target max|u| of the alpha search")
      ->check(CLI::PositiveNumber);
  app.add_option("--second-target", set.second_target, "target max|u| of the second load case")
      ->check(CLI::PositiveNumber);
  app.add_option("--json", set.json_path, "write the results here (default: stdout after the tables)");
  try {
    app.parse(int(ours.size()), ours.data());
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  if (!hs::drivers::output_writable(set.json_path, "--json")) return 2;

  int petsc_argc = int(petsc.size());
  char** petsc_argv = petsc.data();
  int status = 0;
  int my_rank = 0;
  try {
    hs::core::PetscSession petsc_session(&petsc_argc, &petsc_argv, help_text);
    my_rank = hs::core::rank(PETSC_COMM_WORLD);
    hs::mesh::GmshSession gmsh_session;
    MPI_Comm comm = PETSC_COMM_WORLD;
    const bool root = hs::core::rank(comm) == 0;

    std::vector<CaseSpec> cases;
    for (int dim : set.dims) {
      auto sizes = dim == 2 ? set.sizes2d : set.sizes3d;
      std::sort(sizes.begin(), sizes.end(), std::greater<>());
      if (set.quick && sizes.size() > 2) sizes.resize(2);
      for (int p : set.degrees)
        for (double h : sizes) cases.push_back({dim, p, h});
    }

    json out;
    out["benchmark"] = "bench_solver";
    out["machine"] = machine_note(comm);
    out["settings"] = {{"repeats", set.repeats},
                       {"quick", set.quick},
                       {"target", set.target},
                       {"second_target", set.second_target},
                       {"scene",
                        {{"neo_hookean", {{"E", 500.0}, {"nu", 0.49}}},
                         {"dirichlet_patch", {{"center_x", 1.0}, {"radius", 0.5}}},
                         {"gaussian_traction",
                          {{"center_x", -1.0}, {"direction", "e_y"}, {"gamma", 0.2}}},
                         {"mesh", {{"clamp_size", "h/4"}}}}}};
    std::vector<std::string> petsc_args(petsc.begin() + 1, petsc.end());
    out["settings"]["petsc_args"] = petsc_args;
    out["cases"] = json::array();

    std::vector<CaseRecord> recs;
    const double t_all = hs::core::now_seconds();
    for (const auto& cs : cases) {
      CaseRecord rec;
      rec.spec = cs;
      const double t_case = hs::core::now_seconds();
      for (int r = 0; r < set.repeats; ++r) {
        try {
          run_once(set, cs, rec);
        } catch (const std::exception& e) {
          rec.error = e.what();
          break;
        }
        if (root)
          std::cerr << fmt::format("[bench] {}D P{} h={} repeat {}/{}: {} DoFs, alpha {:.5g}, "
                                   "{} its, {:.1f}s so far\n",
                                   cs.dim, cs.degree, cs.h, r + 1, set.repeats,
                                   fmt_count(last(rec, "free_dofs")), last(rec, "alpha"),
                                   fmt_count(last(rec, "full_newton")),
                                   hs::core::now_seconds() - t_case);
      }
      add_checks(rec);
      recs.push_back(rec);
      out["cases"].push_back(to_json(rec));
      out["total_seconds"] = hs::core::now_seconds() - t_all;
      if (root && !set.json_path.empty()) hs::drivers::write_json_atomic(set.json_path, out, "--json");
    }
    if (root) {
      print_tables(std::cout, recs);
      std::cout << fmt::format("\ntotal {:.1f}s on {} ({} cores, {}), {} repeats\n",
                               hs::core::now_seconds() - t_all,
                               out["machine"]["hostname"].get<std::string>(),
                               out["machine"]["nproc"].get<long>(),
                               out["machine"]["petsc_version"].get<std::string>(), set.repeats);
      if (set.json_path.empty()) std::cout << out.dump(2) << "\n";
    }
    // Destroy PETSc objects before the session guards: they are all scoped in run_once.
  } catch (const std::exception& e) {
    std::cerr << fmt::format("[rank {}] {}\n", my_rank, e.what());
    status = 1;
  }
  return status;
}
