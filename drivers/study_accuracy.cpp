/// study_accuracy: what accuracy costs in time (issue 6; write-up in docs/ACCURACY.md).
///
/// The problem of every sample of a dataset: find u and alpha with equilibrium of the
/// compressible Neo-Hookean body (E, nu of the dataset) clamped on the Dirichlet patch
/// |x - p_D| <= r and loaded by alpha g phi(x - p_N) / I_N, such that max|u| = target
/// (NonlinearSolver::solve_for_target). For a fixed set of scenes this driver solves that
/// problem with many settings (mesh size h, degree, quadrature, tolerances, continuation,
/// linear solver, the linear small-strain model) and measures each against a reference:
///
/// Scenes (fixed seeds, the presets' seeds and the dataset defaults for E, nu, r, gamma, h,
/// degree and solver options; every h of a scene discretises the same problem, same p_D):
///   disk    the unit disk, p_D = (1, 0), Random2D's parameters (the seed paper's scene)
///   r2d-0   Random2D shape 0, r2d-1 Random2D shape 1, ood-0 OODRandom2D shape 0
///           (factory::make_shape at every h; the first id from these whose draw is accepted at
///           the same attempt at every h)
///   ball    the unit ball, p_D = (1, 0, 0), Random3D's parameters
///   r3d-0   Random3D shape 0 (drawn at the finest h, its surface remeshed at the coarser ones)
/// (see ShapeCache). Load cases: p_N and g from factory::draw_load_cases on the baseline shape
/// (the preset's h), the targets set to 0.1, 0.3, 0.5 (--tiny: the middle one).
///
/// Reference per scene: P2 on the same shape meshed at h_ref (2D 0.02, 3D 0.2), rtol 1e-10,
/// target_rtol 1e-6, MUMPS LDL^T. Its own discretisation error is estimated by Richardson
/// extrapolation from the ladder h_ref, 2 h_ref, 4 h_ref (3D: two levels; P2, same tolerances): with d1 = ||u_2h - u_h|| and
/// d2 = ||u_4h - u_2h|| (both at the reference's nodes, relative to ||u_h||) the observed order
/// is p = log2(d2 / d1) and the error of u_h about d1 / (2^p - 1) (p clamped to [0.5, 4]; with
/// two levels only, p = 1 is assumed and flagged).
///
/// Metrics per setting and load case: the coarse field is evaluated at the reference's nodes
/// with sampling::MeshSampler (FE interpolant inside the coarse mesh, closest-point extension
/// outside it), then relative L2 and H1 in the seed paper's discrete form
/// (sampling::NodalNorms: nodal values, recovered nodal gradients of the reference mesh), the
/// relative error of alpha, |max|u| / target - 1|, the wall and CPU time of the load case
/// (traction set-up + reset + solve_for_target; median of the repeats), and once per setting the DoFs,
/// the mesh and set-up times and the peak resident memory of the setting (VmHWM after a reset
/// through /proc/self/clear_refs). Settings on the baseline discretisation also get their
/// "solver error": the relative L2 distance at their own nodes to the same discretisation
/// solved with tight tolerances.
///
/// The linear model: u_lin = alpha_lin K(0)^-1 f_ext with alpha_lin = target / max|K(0)^-1
/// f_ext| (one factorisation of the tangent at u = 0 and one solve, on the solver's KSP): the
/// small-strain solution scaled so that its max|u| hits the target exactly.
///
/// One rank only. Sample runs (OPENBLAS_NUM_THREADS=1; times on a shared 2-core VM):
///   study_accuracy --tiny --out results/study_accuracy_tiny.json          (~15-45 s; CI)
///   study_accuracy --full --dims 2 --out results/study_accuracy_2d.json   (~15 min)
///   study_accuracy --full --out results/study_accuracy.json               (scripts/study_accuracy.sh)
/// Arguments after "--" go to PETSc.
#include <malloc.h>
#include <petscksp.h>
#include <petscsnes.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "hypershape/study/machine.hpp"
#include "hypershape/study/output.hpp"
#include "hypershape/config/dataset.hpp"
#include "hypershape/core/error.hpp"
#include "hypershape/core/petsc_handle.hpp"
#include "hypershape/core/timer.hpp"
#include "hypershape/factory/load_cases.hpp"
#include "hypershape/factory/shape_job.hpp"
#include "hypershape/factory/shape_pipeline.hpp"
#include "hypershape/geometry/boundary_check.hpp"
#include "hypershape/geometry/distance.hpp"
#include "hypershape/geometry/random_shape.hpp"
#include "hypershape/geometry/surface_remesh.hpp"
#include "hypershape/mesh/boundary_mesher.hpp"
#include "hypershape/mesh/quality.hpp"
#include "hypershape/mesh/gmsh_mesher.hpp"
#include "hypershape/physics/problem.hpp"
#include "hypershape/physics/registry.hpp"
#include "hypershape/sampling/field_error.hpp"
#include "hypershape/sampling/mesh_sampler.hpp"
#include "hypershape/solver/nonlinear.hpp"

namespace hs = hypershape;
using json = nlohmann::json;

namespace {

constexpr const char* help_text =
    "study_accuracy: the accuracy/time study (see the source header and docs/ACCURACY.md).\n"
    "Options after \"--\" go to PETSc.\n";

// ---- run parameters -------------------------------------------------------------------------

struct Args {
  bool tiny = false, full = false;
  std::string out = "results/study_accuracy.json";
  std::string dump;  ///< tiny check: arrays of one setting and the reference (JSON)
  std::vector<int> dims{2, 3};
  std::vector<std::string> scenes;  ///< empty: all of the mode
  int repeats = -1;                 ///< -1: 3 (full), 1 (tiny)
  double repeat_above = 5.0;        ///< a first run longer than this (s) is not repeated
  double ref_h2d = -1, ref_h3d = -1;
  int ladder = 3;                   ///< reference levels for Richardson (2 or 3)
  bool verbose = false;             ///< a progress line per load case of every setting
  std::string override_yaml;         ///< dataset-config keys over every scene's preset
  bool grid_only = false;           ///< the h x degree grid (and the baseline) only, no knobs
  std::vector<double> sizes2d{0.12, 0.08, 0.04, 0.02, 0.01};
  std::vector<double> sizes3d{0.3, 0.2, 0.1};
  int ladder3d = 2;
  /// Disk references: chord at the patch ends / h (1: ungraded, the default). A graded
  /// reference is more accurate (Richardson L2 estimate 8.5e-4 against 1.9e-3 at h 0.02) but
  /// concentrates its nodes at the patch ends, and the paper's metrics are plain averages over
  /// the nodes: they then weight the singular corners (P1 h 0.16: rel H1 0.24 against 0.13).
  double ref_grading = 1.0;
};

enum class SceneKind { disk, ball, random2d, random3d };

struct SceneSpec {
  std::string name;
  std::string preset;  ///< E, nu, r, gamma, h, degree, solver defaults (and the shape family)
  SceneKind kind = SceneKind::random2d;
  std::int64_t shape_id = 0;
};

/// One way of solving the sample problem.
struct Setting {
  std::string name, group;
  int degree = 1;
  double h = 0;
  int quadrature = 0;  ///< 0: the space's default (2 degree - 1)
  hs::solver::SolverOptions opt;
  std::vector<std::pair<std::string, std::string>> petsc;  ///< without prefix
  bool linear_model = false;
  bool auto_solver = false;  ///< beyond kAutoMumpsDofs unknowns: MUMPS LDL^T (see solve_setting)
  bool graded = false;       ///< on the reference's (graded) mesh of the disk
  /// Diagnostic (2D): the load (p_N and g) rotated by this angle about the origin; on the disk
  /// that is the problem with p_D moved by the same arc length relative to the load.
  double load_rotation = 0;
  bool is_default = false;
  bool baseline_discretisation = false;  ///< same (h, degree, quadrature) as the baseline
};

double median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

json num(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }
std::string fmt_g(double v) { return fmt::format("{:g}", v); }

// ---- memory ---------------------------------------------------------------------------------

double proc_status_mib(const char* key) {
  std::ifstream f("/proc/self/status");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind(key, 0) == 0) {
      std::istringstream s(line.substr(std::string(key).size()));
      double kb = 0;
      s >> kb;
      return kb / 1024.0;
    }
  return NAN;
}
/// Returns freed heap to the system, then resets the peak resident set (VmHWM) to the current
/// one (Linux >= 4.0), so that VmHWM afterwards is the peak of what runs in between.
void reset_peak_rss() {
  malloc_trim(0);
  std::ofstream f("/proc/self/clear_refs");
  f << "5";
}

/// Process CPU time in seconds (what contention on a shared machine inflates far less than wall
/// time; the study runs single-threaded, OPENBLAS_NUM_THREADS=1).
double cpu_now() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

// ---- machine --------------------------------------------------------------------------------

json load_average() {
  std::ifstream f("/proc/loadavg");
  double a = NAN, b = NAN, c = NAN;
  f >> a >> b >> c;
  return json::array({num(a), num(b), num(c)});
}

// ---- scenes and shapes ----------------------------------------------------------------------

/// The scene's preset, with the --override YAML (dataset-config keys) merged over it.
hs::config::DatasetConfig scene_config(const SceneSpec& s, const std::string& override_yaml) {
  return hs::config::parse_dataset_text("preset: " + s.preset + "\n" + override_yaml + "\n",
                                        "<study_accuracy --override>");
}

/// The preset's element size: shapes.h, or the coarser mesh.h of the 3D presets.
double preset_mesh_h(const hs::config::DatasetConfig& cfg) { return std::max(cfg.shapes.h, cfg.shapes.mesh_h); }

/// The shapes of one scene, one per h, all with the same Dirichlet centre p_D (so that every h
/// discretises the same boundary-value problem):
///  - disk / ball: the unit circle / sphere with p_D = (1, 0[, 0]) (the seed paper's scene),
///    resolved at h with vertices exactly on the patch ends (2D: the polygon with the two
///    crossings |x - p_D| = r as vertices; 3D: geometry::remesh_surface of a fine icosphere with
///    the clamp sphere) and meshed by mesh::mesh_boundary as the factory meshes a shape;
///  - random2d: factory::make_shape at every h, with the preset's neck threshold (the factory's
///    own samples at the preset's h; p_D moves with h by
///    up to a quarter of h, see dirichlet_center_offset in the results and docs/ACCURACY.md);
///  - random3d: factory::make_shape drawn at the finest h and meshed at h (mesh_h: its surface
///    remeshed with the same clamp sphere, as the factory's coarse 3D meshes are).
class ShapeCache {
 public:
  ShapeCache(SceneKind kind, hs::factory::ShapeConfig c, std::uint64_t seed, std::int64_t id, double finest_h)
      : kind_(kind), config_(std::move(c)), seed_(seed), id_(id), finest_h_(finest_h) {}
  /// The shape resolved at h; `graded`: the reference variant (the disk's polygon graded
  /// towards the patch ends; the same as the plain one for the other kinds).
  const hs::factory::ShapeSample& at(double h, bool graded = false) {
    graded = graded && kind_ == SceneKind::disk && grade_end_ < 1.0;
    for (auto& [key, s] : shapes_)
      if (std::abs(key.first - h) < 1e-12 && key.second == graded) return *s;
    const double t0 = hs::core::now_seconds();
    auto s = std::make_unique<hs::factory::ShapeSample>(build(h, graded));
    shapes_.emplace_back(std::make_pair(h, graded), std::move(s));
    seconds_.push_back({{h, graded}, hs::core::now_seconds() - t0});
    return *shapes_.back().second;
  }
  double seconds(double h, bool graded = false) const {
    graded = graded && kind_ == SceneKind::disk && grade_end_ < 1.0;
    for (auto& [key, s] : seconds_)
      if (std::abs(key.first - h) < 1e-12 && key.second == graded) return s;
    return NAN;
  }
  void set_grading(double grade_end) { grade_end_ = grade_end; }

 private:
  /// Mesh, patch facets and bookkeeping of a boundary resolved at h.
  hs::factory::ShapeSample finish(hs::geometry::Boundary b, const std::array<double, 3>& p_d, double h) const {
    if (const auto check = hs::geometry::check_boundary(b); !check.ok)
      throw std::runtime_error("boundary at h " + fmt_g(h) + ": " + check.reason);
    hs::factory::ShapeSample out;
    out.shape_id = id_;
    out.boundary = std::move(b);
    hs::mesh::BoundaryMeshOptions mo;
    mo.h = h;
    mo.grading = config_.size_grading;
    out.mesh = hs::mesh::mesh_boundary(out.boundary, mo);
    out.quality = hs::mesh::mesh_quality(out.mesh);
    out.dirichlet_center = p_d;
    out.dirichlet_radius = config_.dirichlet_radius;
    out.dirichlet_facets = hs::geometry::facets_in_ball(out.boundary, p_d, config_.dirichlet_radius);
    return out;
  }
  /// Parameters in [t0, t1) of the points of a unit-circle arc: chords of h_end at both ends,
  /// growing at rate `grading` per unit length, at most h (equidistributed in 1 / size).
  static std::vector<double> arc_parameters(double t0, double t1, double h, double h_end, double grading) {
    const double L = t1 - t0;
    const int n = 20000;
    std::vector<double> cum(n + 1, 0.0);
    auto size = [&](double s) { return std::min(h, h_end + grading * std::min(s, L - s)); };
    for (int i = 0; i < n; ++i) {
      const double s = (i + 0.5) * L / n;
      cum[std::size_t(i) + 1] = cum[std::size_t(i)] + (L / n) / size(s);
    }
    const int m = std::max(1, int(std::ceil(cum[n])));
    std::vector<double> out;
    for (int k = 0, i = 0; k < m; ++k) {
      const double target = cum[n] * k / m;
      while (cum[std::size_t(i) + 1] < target) ++i;
      const double w = (target - cum[std::size_t(i)]) / (cum[std::size_t(i) + 1] - cum[std::size_t(i)]);
      out.push_back(t0 + (i + w) * L / n);
    }
    return out;
  }
  hs::factory::ShapeSample build(double h, bool graded) {
    const double r = config_.dirichlet_radius;
    const std::array<double, 3> e1{1.0, 0.0, 0.0};
    switch (kind_) {
      case SceneKind::disk: {
        // |x - p_D| = r on the unit circle at angle +-theta_c: 2 - 2 cos theta_c = r^2. Each arc
        // (the patch and the rest) is split into chords of at most h; graded (references only):
        // chords of grade_end * h at the patch ends, growing by size_grading per unit length.
        const double tc = std::acos(1.0 - 0.5 * r * r);
        const double pi = std::acos(-1.0);
        const double h_end = graded ? grade_end_ * h : h;
        std::vector<double> xy;
        for (auto [t0, t1] : {std::pair{-tc, tc}, std::pair{tc, 2 * pi - tc}})
          for (double t : arc_parameters(t0, t1, h, h_end, config_.size_grading))
            xy.insert(xy.end(), {std::cos(t), std::sin(t)});
        return finish(hs::geometry::polygon_boundary(std::move(xy)), e1, h);
      }
      case SceneKind::ball: {
        if (!sphere_) sphere_ = hs::geometry::icosphere(6);  // edges ~0.016: sagitta ~3e-5
        hs::geometry::RemeshOptions ro;
        ro.target_edge = h;
        ro.clamp_center = e1;
        ro.clamp_radius = r;
        return finish(hs::geometry::remesh_surface(*sphere_, ro), e1, h);
      }
      case SceneKind::random2d: {
        auto c = config_;
        c.h = h;
        // The neck test at the preset's absolute threshold (min_feature_fraction x the preset's
        // h) at every h: it decides which draw is accepted, and the same draw must be accepted
        // at every h (at 3x the preset's h, Random2D shape 0 and OODRandom2D shapes 0-19 fail
        // the test at its default fraction).
        c.min_feature_fraction = config_.min_feature_fraction * config_.h / h;
        return hs::factory::make_shape(c, std::nullopt, seed_, id_);
      }
      case SceneKind::random3d: {
        // The factory's own coarse mesh (ShapeConfig::mesh_h): the shape drawn at the finest
        // h, its surface remeshed at h with the same clamp sphere. The draw must not change
        // with h (a coarse surface failing its checks would make the factory redraw).
        auto c = config_;
        c.h = finest_h_;
        c.mesh_h = h;
        auto out = hs::factory::make_shape(c, std::nullopt, seed_, id_);
        if (!attempt_) attempt_ = out.attempt;
        if (out.attempt != *attempt_)
          throw std::runtime_error("random3d shape " + std::to_string(id_) + " at h " + fmt_g(h) +
                                   ": the coarse surface fails the factory's checks (draw " +
                                   std::to_string(out.attempt) + " instead of " +
                                   std::to_string(*attempt_) + ")");
        return out;
      }
    }
    throw std::logic_error("scene kind");
  }

  SceneKind kind_;
  hs::factory::ShapeConfig config_;
  std::uint64_t seed_;
  std::int64_t id_;
  double finest_h_;
  std::optional<hs::geometry::Boundary> sphere_;
  std::optional<int> attempt_;  ///< random3d: the draw accepted at the first h built
  double grade_end_ = 1.0;
  std::vector<std::pair<std::pair<double, bool>, std::unique_ptr<hs::factory::ShapeSample>>> shapes_;
  std::vector<std::pair<std::pair<double, bool>, double>> seconds_;
};

/// The shape at another h must come from the same random draw (sub-seed) as the baseline's.
void check_same_draw(const hs::factory::ShapeSample& shape, const hs::factory::ShapeSample& base, double h) {
  if (shape.attempt == base.attempt) return;
  std::string why;
  for (const auto& r : (shape.attempt > base.attempt ? shape : base).rejected)
    why += fmt::format("; attempt {} ({}): {}", r.attempt, r.stage, r.reason);
  throw std::runtime_error(fmt::format("the draw at h {} is attempt {}, the baseline's attempt {}{}", h, shape.attempt,
                                       base.attempt, why));
}

// ---- solving one setting --------------------------------------------------------------------

struct LoadOutcome {
  bool converged = false;
  std::string reason;
  double alpha = NAN, max_u = NAN, seconds = NAN;
  std::vector<double> seconds_all;
  std::vector<double> cpu_seconds_all;  ///< process CPU time of the same runs
  double cpu_seconds = NAN;
  int newton = 0, solves = 0, failed_increments = 0;
  std::vector<double> u;  ///< gathered nodal displacement (canonical order)
};

constexpr std::int64_t kAutoMumpsDofs = 20000;

std::vector<std::pair<std::string, std::string>> mumps_cholesky() {
  return {{"pc_type", "cholesky"}, {"pc_factor_mat_solver_type", "mumps"}};
}

struct SolvedSetting {
  std::string linear_solver;
  std::int64_t dofs = 0, n_vertices = 0, n_cells = 0;
  double seconds_setup = NAN, peak_rss_mib = NAN, rss_before_mib = NAN;
  std::vector<double> nodes;
  std::vector<std::int64_t> cells;
  int nodes_per_cell = 0;
  std::vector<LoadOutcome> loads;
  std::string error;
};

/// Builds the problem of `shape` from the dataset's scene (factory::make_shape_problem) and solves every load case with setting `s`, `repeats` times each (fewer when a
/// run takes longer than `repeat_above` seconds). Never throws for a numerical failure.
/// Called after load case `l` of a setting was solved (at its target), with the solver still
/// at that state: the same-load pass continues the reference from there.
using AfterLoad = std::function<void(std::size_t l, hs::solver::NonlinearSolver&, const hs::physics::Problem&)>;

SolvedSetting solve_setting(const hs::factory::ShapeSample& shape, const hs::config::DatasetConfig& cfg,
                            const std::vector<hs::factory::LoadCase>& cases, const Setting& s, int repeats,
                            double repeat_above, const std::string& prefix, bool verbose,
                            const AfterLoad& after_load = {}) {
  SolvedSetting out;
  reset_peak_rss();
  out.rss_before_mib = proc_status_mib("VmRSS:");
  std::vector<std::pair<std::string, std::string>> petsc = s.petsc;
  try {
    const double t0 = hs::core::now_seconds();
    hs::physics::SpaceOptions so;
    so.degree = s.degree;
    so.quadrature_degree = s.quadrature;
    auto sp = hs::factory::make_shape_problem(PETSC_COMM_SELF, cfg, shape, cases[0], so);
    hs::physics::Problem& problem = *sp.problem;
    // PETSc options of this setting, under its own prefix (removed afterwards). Beyond
    // kAutoMumpsDofs unknowns, settings off the baseline mesh that do not choose a linear solver
    // get MUMPS LDL^T: with PETSc's own Cholesky (the one-rank default, fastest at the default's
    // ~5k unknowns) a Newton iteration of the disk at P2 h 0.02 (74k unknowns) took 1.5 s, with
    // MUMPS 0.6 s.
    if (petsc.empty() && s.auto_solver && problem.space().n_dofs_global() > kAutoMumpsDofs) petsc = mumps_cholesky();
    for (const auto& [k, v] : petsc)
      HS_PETSC(PetscOptionsSetValue(nullptr, ("-" + prefix + k).c_str(), v.empty() ? nullptr : v.c_str()));
    out.linear_solver = petsc.empty() ? "petsc cholesky (default)" : "";
    for (const auto& [k, v] : petsc) out.linear_solver += (out.linear_solver.empty() ? "-" : " -") + k + " " + v;
    hs::solver::NonlinearSolver nl(problem, s.opt, prefix);
    out.seconds_setup = hs::core::now_seconds() - t0;
    const auto& space = problem.space();
    out.dofs = space.n_dofs_global();
    out.n_vertices = space.n_vertices_global();
    out.n_cells = space.n_cells_global();
    out.nodes = space.canonical_coords();
    out.cells = space.canonical_cells();
    out.nodes_per_cell = int(out.cells.size() / std::size_t(out.n_cells));
    hs::core::VecH du = problem.create_vector();
    for (auto lc : cases) {
      if (s.load_rotation != 0) {
        const double c = std::cos(s.load_rotation), sn = std::sin(s.load_rotation);
        for (auto* v : {&lc.center, &lc.direction}) {
          const double x = (*v)[0], y = (*v)[1];
          (*v)[0] = c * x - sn * y;
          (*v)[1] = sn * x + c * y;
        }
      }
      LoadOutcome lo;
      for (int r = 0; r < repeats; ++r) {
        const double t1 = hs::core::now_seconds(), c1 = cpu_now();
        sp.set_load_case(cfg, shape, lc);
        nl.reset();
        if (s.linear_model) {
          // The small-strain model: K(0) du = f_ext, scaled so that max|u| = target.
          Mat J = nl.jacobian_matrix();
          KSP ksp;
          HS_PETSC(SNESGetKSP(nl.snes(), &ksp));
          lo.converged = problem.jacobian(nl.solution(), J);
          if (lo.converged) {
            HS_PETSC(KSPSetOperators(ksp, J, J));
            HS_PETSC(KSPSolve(ksp, problem.load(), du));
            KSPConvergedReason why;
            HS_PETSC(KSPGetConvergedReason(ksp, &why));
            const double m = problem.max_displacement(du);
            lo.converged = why > 0 && m > 0 && std::isfinite(m);
            lo.reason = KSPConvergedReasons[why];
            lo.alpha = lc.target / m;
            HS_PETSC(VecScale(du, lo.alpha));
            lo.max_u = problem.max_displacement(du);
            lo.solves = 1;
          } else {
            lo.reason = "tangent at u = 0 not formed";
          }
        } else {
          const auto tr = nl.solve_for_target(lc.target);
          lo.converged = tr.converged;
          lo.reason = tr.reason;
          lo.alpha = tr.alpha;
          lo.max_u = problem.max_displacement(nl.solution());
          lo.newton = tr.newton_iterations;
          lo.solves = tr.solves;
          lo.failed_increments = tr.failed_increments;
        }
        const double t = hs::core::now_seconds() - t1;
        lo.seconds_all.push_back(t);
        lo.cpu_seconds_all.push_back(cpu_now() - c1);
        if (!lo.converged || t > repeat_above) break;
      }
      lo.seconds = median(lo.seconds_all);
      lo.cpu_seconds = median(lo.cpu_seconds_all);
      if (verbose)
        std::cerr << fmt::format("[study]   {} load {}/{}: {} ({} Newton its, {} solves), {:.2f} s x {}\n", s.name,
                                 out.loads.size() + 1, cases.size(), lo.converged ? "ok" : "FAILED: " + lo.reason,
                                 lo.newton, lo.solves, lo.seconds, lo.seconds_all.size());
      if (lo.converged) {
        const auto f = problem.gather(s.linear_model ? du.get() : nl.solution());
        lo.u = f.values;
        for (double v : lo.u)
          if (!std::isfinite(v)) {
            lo.converged = false;
            lo.reason = "non-finite displacement";
            break;
          }
      }
      if (lo.converged && after_load) after_load(out.loads.size(), nl, problem);
      out.loads.push_back(std::move(lo));
    }
  } catch (const std::exception& e) {
    out.error = e.what();
  }
  for (const auto& [k, v] : petsc) HS_PETSC(PetscOptionsClearValue(nullptr, ("-" + prefix + k).c_str()));
  out.peak_rss_mib = proc_status_mib("VmHWM:");
  return out;
}

// ---- the reference --------------------------------------------------------------------------

/// What every setting is compared with: the finest solve of one scene, at its nodes.
struct Reference {
  double h = 0;
  std::vector<double> nodes;
  std::vector<std::int64_t> cells;
  int nodes_per_cell = 0;
  std::unique_ptr<hs::sampling::NodalNorms> norms;
  std::unique_ptr<hs::geometry::SignedDistance> sdf;  ///< of the reference boundary
  std::vector<std::vector<double>> u;                 ///< per load case
  std::vector<double> alpha;
  json record;
};

/// Evaluates the field of a solved setting at the reference's nodes.
std::vector<std::vector<double>> at_reference(const hs::factory::ShapeSample& shape, const SolvedSetting& s,
                                              const Reference& ref, int d) {
  hs::sampling::MeshSampler sampler(d, s.nodes_per_cell == d + 1 ? 1 : 2, s.nodes, s.cells, shape.boundary,
                                    ref.nodes);
  std::vector<std::vector<double>> out;
  for (const auto& lo : s.loads) out.push_back(lo.converged ? sampler.interpolate(lo.u, d) : std::vector<double>{});
  return out;
}

double rel_l2_diff(const std::vector<double>& a, const std::vector<double>& b, const std::vector<double>& ref, int d) {
  std::vector<double> diff(a.size());
  for (std::size_t i = 0; i < a.size(); ++i) diff[i] = a[i] - b[i];
  return hs::sampling::discrete_l2_norm(diff, d) / hs::sampling::discrete_l2_norm(ref, d);
}
double rel_h1_diff(const hs::sampling::NodalNorms& nn, const std::vector<double>& a, const std::vector<double>& b,
                   const std::vector<double>& ref, int d) {
  std::vector<double> diff(a.size());
  for (std::size_t i = 0; i < a.size(); ++i) diff[i] = a[i] - b[i];
  return nn.h1_norm(diff, d) / nn.h1_norm(ref, d);
}

/// Richardson: the observed order from the differences of consecutive levels and the error of
/// the finest. d1 = |finest - next|, d2 = |next - coarsest| (d2 NaN with two levels).
json richardson(double d1, double d2) {
  json r;
  r["d1"] = num(d1);
  r["d2"] = num(d2);
  double p = NAN;
  bool assumed = false;
  if (std::isfinite(d2) && d1 > 0 && d2 > 0) p = std::log2(d2 / d1);
  double pu = p;
  if (!std::isfinite(p)) {
    pu = 1.0;
    assumed = true;
  }
  const bool clamped = std::isfinite(p) && (p < 0.5 || p > 4.0);
  pu = std::clamp(pu, 0.5, 4.0);
  r["order_observed"] = num(p);
  r["order_used"] = pu;
  r["order_assumed"] = assumed;
  r["order_clamped"] = clamped;
  r["estimate"] = num(d1 / (std::pow(2.0, pu) - 1.0));
  return r;
}

double mean_of(const std::vector<double>& v);

// ---- the same-load error ---------------------------------------------------------------------

/// One setting's answer to one load case, evaluated at the reference's nodes.
struct SameLoad {
  std::size_t result = 0, load = 0;  ///< index in the scene's results, load case
  double alpha = NAN;
  std::vector<double> u;
};

/// The error of a sample as a training pair. The metrics above compare u at the same target
/// max|u|, where a too-stiff discretisation is compensated by a larger alpha; but a dataset
/// pairs u with the traction alpha g phi it was solved for, so what a model learns is off by
/// |u_h(alpha_h) - u(alpha_h)|. This pass re-solves the reference at its target (the state the
/// metrics above compare with), then continues it by load control through every setting's
/// alpha in ascending order, and stores "same_load_rel_l2" / "same_load_rel_h1" per load case
/// (and their means in the summary). A continuation that fails leaves them null, with a reason.
void same_load_pass(json& sc, const hs::factory::ShapeSample& ref_shape, const hs::config::DatasetConfig& cfg,
                    const std::vector<hs::factory::LoadCase>& cases, const Setting& ref_set, const Reference& ref,
                    std::vector<SameLoad>& answers, const std::string& prefix, int d) {
  const double t0 = hs::core::now_seconds();
  std::sort(answers.begin(), answers.end(), [](const SameLoad& x, const SameLoad& y) {
    return std::tie(x.load, x.alpha) < std::tie(y.load, y.alpha);
  });
  int n_ok = 0, n_failed = 0;
  auto after = [&](std::size_t l, hs::solver::NonlinearSolver& nl, const hs::physics::Problem& problem) {
    for (auto& ans : answers) {
      if (ans.load != l) continue;
      json& lj = sc["results"][ans.result]["loads"][l];
      const auto r = nl.solve(ans.alpha);
      if (!r.converged) {
        lj["same_load_error"] = "reference continuation to alpha " + std::to_string(ans.alpha) + ": " + r.reason;
        ++n_failed;
        continue;
      }
      const std::vector<double> u = problem.gather(nl.solution()).values;
      lj["same_load_rel_l2"] = num(ref.norms->rel_l2(u, ans.u, d));
      lj["same_load_rel_h1"] = num(ref.norms->rel_h1(u, ans.u, d));
      lj["same_load_ref_max_u"] = num(r.max_displacement);
      ++n_ok;
    }
  };
  Setting s = ref_set;
  s.name = "reference (same-load pass)";
  const auto solved = solve_setting(ref_shape, cfg, cases, s, 1, 0.0, prefix, false, after);
  for (std::size_t l = 0; l < solved.loads.size(); ++l)
    if (!solved.loads[l].converged) n_failed += int(std::count_if(answers.begin(), answers.end(),
                                                                    [l](const SameLoad& x) { return x.load == l; }));
  if (!solved.error.empty()) std::cerr << "[study] same-load pass: " << solved.error << "\n";
  for (auto& r : sc["results"]) {
    if (!r.contains("loads")) continue;
    std::vector<double> l2, h1;
    for (const auto& lj : r["loads"])
      if (lj.contains("same_load_rel_l2") && lj["same_load_rel_l2"].is_number()) {
        l2.push_back(lj["same_load_rel_l2"].get<double>());
        h1.push_back(lj["same_load_rel_h1"].get<double>());
      }
    const bool all = l2.size() == r["loads"].size() && !l2.empty();
    r["summary"]["same_load_rel_l2"] = num(all ? mean_of(l2) : NAN);
    r["summary"]["same_load_rel_h1"] = num(all ? mean_of(h1) : NAN);
  }
  sc["same_load_pass"] = {{"solves", n_ok}, {"failed", n_failed}, {"seconds", num(hs::core::now_seconds() - t0)}};
  std::cerr << fmt::format("[study] same-load pass: {} reference solves, {} failed, {:.1f} s\n", n_ok, n_failed,
                           hs::core::now_seconds() - t0);
}

// ---- settings -------------------------------------------------------------------------------

/// The settings of one scene: the baseline = the preset's defaults (h, degree, SolverOptions,
/// the one-rank linear solver), the h x degree grid, and one knob at a time from the baseline.
/// 3D runs the grid, the linear model and two linear solvers only (each 3D solve costs seconds
/// to minutes here; the tolerance and continuation knobs act the same way in 2D and 3D).
std::vector<Setting> make_settings(int dim, const Args& a, const hs::config::DatasetConfig& cfg, double ref_h,
                                   SceneKind scene_kind) {
  std::vector<Setting> out;
  const double h0 = preset_mesh_h(cfg);
  const int p0 = cfg.degree;
  const bool tiny = a.tiny;
  Setting base;
  base.degree = p0;
  base.h = h0;
  base.opt = cfg.solver;
  auto add = [&](Setting s) {
    s.baseline_discretisation =
        s.h == h0 && s.degree == p0 && s.quadrature == 0 && !s.linear_model && s.load_rotation == 0;
    s.is_default = s.group == "mesh" && s.h == h0 && s.degree == p0;
    // 3D: MUMPS everywhere beyond kAutoMumpsDofs, the baseline included: PETSc's own Cholesky
    // (the one-rank default) took 233 s for one load case of the ball at P1 h 0.1 (25k unknowns,
    // 3 Newton iterations) where MUMPS LDL^T took 6.8 s (docs/ACCURACY.md).
    s.auto_solver = dim == 3 || !(s.h == h0 && s.degree == p0);
    out.push_back(std::move(s));
  };
  auto knob = [&](const std::string& group, const std::string& what, auto&& change) {
    Setting s = base;
    change(s);
    s.name = fmt::format("P{} h{} {}", s.degree, fmt_g(s.h), what);
    s.group = group;
    add(s);
  };
  // First: the baseline discretisation at tight tolerances (the solver-error yardstick).
  if (dim == 2)
    knob("tolerance", "tight", [](Setting& s) {
      s.opt.rtol = 1e-10;
      s.opt.target_rtol = 1e-6;
    });
  std::vector<double> sizes = dim == 2 ? a.sizes2d : a.sizes3d;
  if (tiny) sizes = {0.16, 0.08, 0.04};
  std::sort(sizes.begin(), sizes.end(), std::greater<>());
  for (int p : {1, 2})
    for (double h : sizes) {
      if (p == 2 && h <= ref_h * 1.0001) continue;  // the reference's mesh or finer
      Setting s = base;
      s.degree = p;
      s.h = h;
      s.name = fmt::format("P{} h{}", p, fmt_g(h));
      s.group = "mesh";
      add(s);
    }
  knob("linear_model", "linear", [](Setting& s) { s.linear_model = true; });
  if (tiny || a.grid_only) return out;
  if (dim == 2) {
    knob("linear_model", "linear", [](Setting& s) {
      s.linear_model = true;
      s.degree = 2;
    });
    // Quadrature: only P2 has a choice that matters (P1 gradients are constant per cell).
    for (int q : {2, 4, 6})
      knob("quadrature", fmt::format("quad {}", q), [q](Setting& s) {
        s.degree = 2;
        s.h = 0.08;
        s.quadrature = q;
      });
    for (double rtol : {1e-6, 1e-12})
      knob("newton_rtol", fmt::format("rtol {:g}", rtol), [rtol](Setting& s) { s.opt.rtol = rtol; });
    for (double t : {1e-2, 1e-4})
      knob("target_rtol", fmt::format("target_rtol {:g}", t), [t](Setting& s) { s.opt.target_rtol = t; });
    knob("control", "load control", [](Setting& s) { s.opt.control = hs::solver::Control::load; });
    knob("path_rtol", "path_rtol 0.01", [](Setting& s) { s.opt.path_rtol = 1e-2; });
    if (scene_kind == SceneKind::disk)
      // How much a small move of p_D alone changes u (the p_D of random 2D shapes moves with h):
      // on the reference's own mesh and on the default's.
      for (auto [p, h] : {std::pair{1, h0}, std::pair{2, ref_h}})
        knob("diagnostic", "p_D moved 0.003", [p = p, h = h, g = p == 2](Setting& s) {
          s.degree = p;
          s.h = h;
          s.graded = g;  // P2: on the reference's own mesh, so only p_D differs
          s.load_rotation = -0.003;
        });
  }
  using Opts = std::vector<std::pair<std::string, std::string>>;
  std::vector<std::pair<std::string, Opts>> solvers{
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
    if (dim == 3 && name != "gmres+hypre") continue;
    knob("linear_solver", name, [&opts = opts](Setting& s) { s.petsc = opts; });
  }
  return out;
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
  j["control"] = s.opt.control == hs::solver::Control::displacement ? "displacement" : "load";
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

// ---- output ---------------------------------------------------------------------------------

std::string fmt_e(const json& v) { return v.is_null() ? "-" : fmt::format("{:.2e}", v.get<double>()); }
std::string fmt_s(const json& v) {
  if (v.is_null()) return "-";
  const double s = v.get<double>();
  return s < 1 ? fmt::format("{:.0f} ms", s * 1e3) : fmt::format("{:.2f} s", s);
}

void print_table(std::ostream& os, const json& out) {
  for (const auto& sc : out["scenes"]) {
    os << fmt::format("\n### {} ({}D, {} shape {})\n\n", sc["name"].get<std::string>(), sc.value("dim", 0),
                      sc["preset"].get<std::string>(), sc["shape_id"].get<long>());
    if (sc.contains("error")) {
      os << "error: " << sc["error"].get<std::string>() << "\n";
      continue;
    }
    const auto& ref = sc["reference"];
    os << fmt::format("reference: P2 h {} ({} DoFs), estimated own error rel L2 {} / H1 {} / alpha {}\n\n",
                      ref["h"].get<double>(), ref["dofs"].get<long>(), fmt_e(ref["richardson_l2_mean"]),
                      fmt_e(ref["richardson_h1_mean"]), fmt_e(ref["richardson_alpha_mean"]));
    os << "| setting | DoFs | time/load | rel L2 | rel H1 | alpha err | same-load L2 | solver err | peak RSS +MiB | ok |\n"
          "|---|---|---|---|---|---|---|---|---|---|\n";
    for (const auto& r : sc["results"]) {
      const auto& m = r["summary"];
      os << fmt::format("| {}{} | {} | {} | {} | {} | {} | {} | {} | {} | {}/{} |\n",
                        r["setting"]["name"].get<std::string>(), r["setting"]["is_default"].get<bool>() ? " (default)" : "",
                        r.value("dofs", json(0)).get<long>(), fmt_s(m["seconds_per_load"]), fmt_e(m["rel_l2"]),
                        fmt_e(m["rel_h1"]), fmt_e(m["alpha_err"]), fmt_e(m.value("same_load_rel_l2", json())),
                        fmt_e(m["solver_l2"]),
                        r["peak_rss_delta_mib"].is_null() ? "-" : fmt::format("{:.0f}", r["peak_rss_delta_mib"].get<double>()),
                        m["converged"].get<int>(), m["loads"].get<int>());
    }
  }
}

double mean_of(const std::vector<double>& v) {
  double s = 0;
  int n = 0;
  for (double x : v)
    if (std::isfinite(x)) s += x, ++n;
  return n ? s / n : NAN;
}

}  // namespace

int main(int argc, char** argv) {
  auto [ours, petsc] = hs::study::split_at_dashes(argc, argv);
  Args a;
  CLI::App app{"The accuracy/time study (docs/ACCURACY.md). Arguments after \"--\" go to PETSc."};
  auto* tiny = app.add_flag("--tiny", a.tiny, "CI version: the disk, P1/P2 at coarse h, a coarse reference, 1 load case");
  app.add_flag("--full", a.full, "the whole study (default)")->excludes(tiny);
  app.add_option("--out", a.out, "JSON results (default results/study_accuracy.json)");
  app.add_option("--dump", a.dump, "also write the arrays of one setting and the reference (JSON) for checks");
  app.add_option("--dims", a.dims, "dimensions to run (full mode)")->check(CLI::IsMember({2, 3}));
  app.add_option("--scenes", a.scenes, "scene names to run (disk r2d-0 r2d-1 ood-0 easy-0 ball r3d-0)");
  app.add_option("--repeats", a.repeats, "repeats per load case (default 3; tiny 1)")->check(CLI::Range(1, 50));
  app.add_option("--repeat-above", a.repeat_above, "a load case whose first run takes longer (s) is not repeated")
      ->check(CLI::PositiveNumber);
  app.add_option("--ref-h2d", a.ref_h2d, "reference mesh size in 2D (default 0.02)")->check(CLI::PositiveNumber);
  app.add_option("--ref-h3d", a.ref_h3d, "reference mesh size in 3D (default 0.2)")->check(CLI::PositiveNumber);
  app.add_option("--override", a.override_yaml,
                 "dataset-config YAML merged over every scene's preset, e.g. 'shapes: {max_turn_deg: 30}'");
  app.add_flag("--grid-only", a.grid_only, "the h x degree grid and the linear model only (no tolerance, "
               "control, quadrature or linear-solver knobs)");
  app.add_flag("-v,--verbose", a.verbose, "a progress line per load case (always for the reference)");
  app.add_option("--ladder", a.ladder, "2D reference levels for Richardson: 2 or 3")->check(CLI::Range(2, 3));
  app.add_option("--ladder3d", a.ladder3d, "3D reference levels for Richardson: 2 or 3")->check(CLI::Range(2, 3));
  app.add_option("--ref-grading", a.ref_grading,
                 "disk references: boundary chord at the patch ends as a fraction of h (default 1: "
                 "ungraded; graded references weight the patch ends in the node-averaged metrics)")
      ->check(CLI::Range(0.01, 1.0));
  app.add_option("--sizes2d", a.sizes2d, "2D mesh sizes of the h x degree grid (full)")->check(CLI::PositiveNumber);
  app.add_option("--sizes3d", a.sizes3d, "3D mesh sizes of the h x degree grid (full)")->check(CLI::PositiveNumber);
  try {
    app.parse(int(ours.size()), ours.data());
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  if (!hs::study::output_writable(a.out, "--out") || !hs::study::output_writable(a.dump, "--dump")) return 2;
  if (a.repeats < 0) a.repeats = a.tiny ? 1 : 3;
  if (a.ref_h2d < 0) a.ref_h2d = 0.02;
  if (a.ref_h3d < 0) a.ref_h3d = 0.2;

  int petsc_argc = int(petsc.size());
  char** petsc_argv = petsc.data();
  int status = 0;
  try {
    hs::core::PetscSession petsc_session(&petsc_argc, &petsc_argv, help_text);
    if (hs::core::size(PETSC_COMM_WORLD) != 1) throw std::runtime_error("study_accuracy runs on one rank");
    hs::mesh::GmshSession gmsh_session;

    std::vector<SceneSpec> specs;
    if (a.tiny) {
      specs = {{"disk", "random2d", SceneKind::disk, 0}};
    } else {
      const std::vector<SceneSpec> all{{"disk", "random2d", SceneKind::disk, 0},
                                       {"r2d-0", "random2d", SceneKind::random2d, 0},
                                       {"r2d-1", "random2d", SceneKind::random2d, 1},
                                       {"ood-0", "ood_random2d", SceneKind::random2d, 0},
                                       {"easy-0", "easy_random2d", SceneKind::random2d, 0},
                                       {"ball", "random3d", SceneKind::ball, 0},
                                       {"r3d-0", "random3d", SceneKind::random3d, 0}};
      for (const auto& s : all) {
        const int dim = s.preset == "random3d" ? 3 : 2;
        if (std::find(a.dims.begin(), a.dims.end(), dim) == a.dims.end()) continue;
        if (!a.scenes.empty() && std::find(a.scenes.begin(), a.scenes.end(), s.name) == a.scenes.end()) continue;
        specs.push_back(s);
      }
    }

    json out;
    out["study"] = "study_accuracy";
    out["mode"] = a.tiny ? "tiny" : "full";
    out["machine"] = hs::study::machine_note();
    out["load_average_start"] = load_average();
    out["parameters"] = {{"repeats", a.repeats},
                         {"repeat_above_seconds", a.repeat_above},
                         {"ref_h2d", a.ref_h2d},
                         {"ref_h3d", a.ref_h3d},
                         {"ladder", a.ladder},
                         {"ladder3d", a.ladder3d},
                         {"ref_grading_disk", a.ref_grading},
                         {"sizes2d", a.sizes2d},
                         {"sizes3d", a.sizes3d},
                         {"override", a.override_yaml},
                         {"grid_only", a.grid_only},
                         {"reference_rtol", 1e-10},
                         {"reference_target_rtol", 1e-6},
                         {"petsc_args", std::vector<std::string>(petsc.begin() + 1, petsc.end())}};
    out["scenes"] = json::array();
    const double t_all = hs::core::now_seconds();
    int setting_counter = 0;

    for (const auto& spec : specs) {
      json sc;
      sc["name"] = spec.name;
      sc["preset"] = spec.preset;
      sc["kind"] = spec.kind == SceneKind::disk       ? "disk"
                   : spec.kind == SceneKind::ball     ? "ball"
                   : spec.kind == SceneKind::random2d ? "random2d"
                                                      : "random3d";
      sc["shape_id"] = spec.shape_id;
      sc["shape_id_requested"] = spec.shape_id;
      const double t_scene = hs::core::now_seconds();
      try {
        const auto cfg = scene_config(spec, a.override_yaml);
        const int d = cfg.shapes.dim;
        sc["dim"] = d;
        sc["material"] = {{"E", cfg.material.E}, {"nu", cfg.material.nu}};
        sc["gamma"] = cfg.loads.gamma;
        sc["dirichlet_radius"] = cfg.shapes.dirichlet_radius;
        sc["seed"] = cfg.seed;
        sc["loads_per_shape_in_preset"] = cfg.loads.count;
        const double ref_h = d == 2 ? a.ref_h2d : a.ref_h3d;
        const auto settings = make_settings(d, a, cfg, ref_h, spec.kind);
        // The shape: the first id from the requested one whose draw is accepted at the same
        // attempt (sub-seed) at every h of the study, so that every h meshes the same random
        // shape (the mesh quality gate or the thinnest-feature test, both h-dependent, may
        // accept another attempt at another h).
        std::vector<double> all_h{cfg.shapes.h, preset_mesh_h(cfg)};
        const int n_levels = d == 2 ? a.ladder : a.ladder3d;
        for (int level = 0; level < n_levels; ++level) all_h.push_back(ref_h * std::pow(2.0, level));
        for (const auto& s : settings) all_h.push_back(s.h);
        std::unique_ptr<ShapeCache> cache;
        json skipped = json::array();
        const double finest_h = *std::min_element(all_h.begin(), all_h.end());
        for (std::int64_t id = spec.shape_id; id < spec.shape_id + 20 && !cache; ++id) {
          auto c = std::make_unique<ShapeCache>(spec.kind, cfg.shapes, cfg.seed, id, finest_h);
          c->set_grading(a.ref_grading);
          try {
            const auto& b = c->at(preset_mesh_h(cfg));
            if (spec.kind == SceneKind::random2d)
              for (double h : all_h) check_same_draw(c->at(h), b, h);
            cache = std::move(c);
          } catch (const std::exception& e) {
            skipped.push_back({{"shape_id", id}, {"why", e.what()}});
            std::cerr << fmt::format("[study] {}: shape {} skipped: {}\n", spec.name, id, e.what());
          }
        }
        if (!cache) throw std::runtime_error("no shape id with the same draw at every h in 20 tries");
        ShapeCache& shapes = *cache;
        // The load cases are drawn on the shape at the resolution it is drawn at (shapes.h):
        // p_N is a uniform boundary point and so moves with the facets (see "p_D moves with h"
        // in docs/ACCURACY.md); drawn on the preset's coarser 3D mesh they would be other load
        // cases, and the study would not compare with its earlier runs.
        const auto& base_shape = shapes.at(cfg.shapes.h);
        sc["shape_id"] = base_shape.shape_id;
        sc["shape_ids_skipped"] = skipped;
        sc["attempt"] = base_shape.attempt;
        // Load cases: p_N, g drawn as the factory draws them; targets spread over the range.
        auto loads = cfg.loads;
        loads.count = 3;
        auto cases = hs::factory::draw_load_cases(base_shape, loads, cfg.seed);
        const std::vector<double> targets{0.1, 0.3, 0.5};
        for (std::size_t l = 0; l < cases.size(); ++l) cases[l].target = targets[l];
        if (a.tiny) cases = {cases[1]};
        sc["load_cases"] = json::array();
        for (const auto& lc : cases)
          sc["load_cases"].push_back({{"p_n", std::vector<double>(lc.center.begin(), lc.center.begin() + d)},
                                      {"g", std::vector<double>(lc.direction.begin(), lc.direction.begin() + d)},
                                      {"target", lc.target}});

        // ---- reference and its ladder ----
        Setting ref_set;
        ref_set.degree = 2;
        ref_set.opt = cfg.solver;
        ref_set.opt.rtol = 1e-10;
        ref_set.opt.target_rtol = 1e-6;
        ref_set.petsc = mumps_cholesky();
        Reference ref;
        ref.h = ref_h;
        std::vector<std::vector<std::vector<double>>> ladder_u;  // level -> load -> field at ref nodes
        std::vector<std::vector<double>> ladder_alpha;
        json ladder_j = json::array();
        for (int level = 0; level < n_levels; ++level) {
          const double h = ref_h * std::pow(2.0, level);
          ref_set.h = h;
          ref_set.name = fmt::format("reference P2 h{}", fmt_g(h));
          const double t0 = hs::core::now_seconds();
          json lj;
          lj["h"] = h;
          try {
            const auto& shape = shapes.at(h, true);
            check_same_draw(shape, base_shape, h);
            auto solved = solve_setting(shape, cfg, cases, ref_set, 1, 0.0, fmt::format("s{}_", setting_counter++), true);
            if (!solved.error.empty()) throw std::runtime_error(solved.error);
            lj["dofs"] = solved.dofs;
            lj["linear_solver"] = solved.linear_solver;
            lj["vertices"] = solved.n_vertices;
            lj["seconds_mesh"] = num(shapes.seconds(h, true));
            lj["seconds_setup"] = num(solved.seconds_setup);
            lj["peak_rss_mib"] = num(solved.peak_rss_mib);
            lj["peak_rss_delta_mib"] = num(solved.peak_rss_mib - solved.rss_before_mib);
            json per = json::array();
            for (const auto& lo : solved.loads)
              per.push_back({{"converged", lo.converged}, {"reason", lo.reason}, {"alpha", num(lo.alpha)},
                             {"max_u", num(lo.max_u)}, {"seconds", num(lo.seconds)}, {"newton", lo.newton}});
            lj["loads"] = per;
            for (const auto& lo : solved.loads)
              if (!lo.converged) throw std::runtime_error("a reference load case failed: " + lo.reason);
            if (level == 0) {
              ref.nodes = solved.nodes;
              ref.cells = solved.cells;
              ref.nodes_per_cell = solved.nodes_per_cell;
              ref.norms = std::make_unique<hs::sampling::NodalNorms>(d, ref.nodes, ref.cells, ref.nodes_per_cell);
              ref.sdf = std::make_unique<hs::geometry::SignedDistance>(shape.boundary);
              for (auto& lo : solved.loads) {
                ref.u.push_back(lo.u);
                ref.alpha.push_back(lo.alpha);
              }
              ladder_u.push_back(ref.u);
              ref.record["dofs"] = solved.dofs;
              ref.record["vertices"] = solved.n_vertices;
              ref.record["nodes"] = ref.nodes.size() / std::size_t(d);
              ref.record["alpha"] = ref.alpha;
              ref.record["dirichlet_center"] = shape.dirichlet_center;
            } else {
              ladder_u.push_back(at_reference(shape, solved, ref, d));
            }
            std::vector<double> al;
            for (auto& lo : solved.loads) al.push_back(lo.alpha);
            ladder_alpha.push_back(al);
          } catch (const std::exception& e) {
            if (level == 0) throw;
            lj["error"] = e.what();
            std::cerr << fmt::format("[study] {}: ladder level h {} failed: {}\n", spec.name, h, e.what());
            ladder_j.push_back(lj);
            break;  // the levels must be consecutive
          }
          lj["seconds_total"] = hs::core::now_seconds() - t0;
          std::cerr << fmt::format("[study] {}: reference ladder P2 h {}: {} DoFs, {:.1f} s\n", spec.name, h,
                                   lj.value("dofs", json(0)).get<long>(), lj["seconds_total"].get<double>());
          ladder_j.push_back(lj);
        }
        ref.record["h"] = ref_h;
        ref.record["graded"] = spec.kind == SceneKind::disk && a.ref_grading < 1.0;
        ref.record["grading_end_fraction"] = ref.record["graded"].get<bool>() ? a.ref_grading : 1.0;
        ref.record["degree"] = 2;
        ref.record["ladder"] = ladder_j;
        // Richardson per load case, for L2, H1 and alpha.
        json rich = json::array();
        std::vector<double> est_l2, est_h1, est_alpha;
        for (std::size_t l = 0; l < cases.size(); ++l) {
          json rj;
          const auto& u0 = ref.u[l];
          double d1l2 = NAN, d2l2 = NAN, d1h1 = NAN, d2h1 = NAN, d1a = NAN, d2a = NAN;
          if (ladder_u.size() >= 2) {
            d1l2 = rel_l2_diff(ladder_u[1][l], u0, u0, d);
            d1h1 = rel_h1_diff(*ref.norms, ladder_u[1][l], u0, u0, d);
            d1a = std::abs(ladder_alpha[1][l] - ladder_alpha[0][l]) / ladder_alpha[0][l];
          }
          if (ladder_u.size() >= 3) {
            d2l2 = rel_l2_diff(ladder_u[2][l], ladder_u[1][l], u0, d);
            d2h1 = rel_h1_diff(*ref.norms, ladder_u[2][l], ladder_u[1][l], u0, d);
            d2a = std::abs(ladder_alpha[2][l] - ladder_alpha[1][l]) / ladder_alpha[0][l];
          }
          rj["l2"] = richardson(d1l2, d2l2);
          rj["h1"] = richardson(d1h1, d2h1);
          rj["alpha"] = richardson(d1a, d2a);
          est_l2.push_back(rj["l2"]["estimate"].is_null() ? NAN : rj["l2"]["estimate"].get<double>());
          est_h1.push_back(rj["h1"]["estimate"].is_null() ? NAN : rj["h1"]["estimate"].get<double>());
          est_alpha.push_back(rj["alpha"]["estimate"].is_null() ? NAN : rj["alpha"]["estimate"].get<double>());
          rich.push_back(rj);
        }
        ref.record["richardson"] = rich;
        ref.record["richardson_l2_mean"] = num(mean_of(est_l2));
        ref.record["richardson_h1_mean"] = num(mean_of(est_h1));
        ref.record["richardson_alpha_mean"] = num(mean_of(est_alpha));
        sc["reference"] = ref.record;
        std::cerr << fmt::format("[study] {}: reference P2 h {}: estimated own error rel L2 {:.2e}, H1 {:.2e}, "
                                 "alpha {:.2e} (Richardson, order {})\n",
                                 spec.name, ref_h, mean_of(est_l2), mean_of(est_h1), mean_of(est_alpha),
                                 rich[0]["l2"]["order_used"].get<double>());

        // ---- the settings ----
        // Baseline discretisation at tight tolerances, per load case (empty: not available).
        std::vector<std::vector<double>> tight_u(cases.size());
        std::vector<SameLoad> same_load;  // the settings' answers, for the same-load pass below
        sc["results"] = json::array();
        bool dumped = false;
        for (const auto& s : settings) {
          json r;
          r["setting"] = setting_json(s);
          try {
            const auto& shape = shapes.at(s.h, s.graded);
            check_same_draw(shape, base_shape, s.h);
            auto solved = solve_setting(shape, cfg, cases, s, a.repeats, a.repeat_above,
                                        fmt::format("s{}_", setting_counter++), a.verbose);
            if (!solved.error.empty()) throw std::runtime_error(solved.error);
            r["dofs"] = solved.dofs;
            r["linear_solver"] = solved.linear_solver;
            r["vertices"] = solved.n_vertices;
            r["cells"] = solved.n_cells;
            r["seconds_mesh"] = num(shapes.seconds(s.h, s.graded));
            r["seconds_setup"] = num(solved.seconds_setup);
            r["peak_rss_mib"] = num(solved.peak_rss_mib);
            r["rss_before_mib"] = num(solved.rss_before_mib);
            r["peak_rss_delta_mib"] = num(solved.peak_rss_mib - solved.rss_before_mib);
            // How far this shape is from the reference's: boundary points vs the reference boundary.
            {
              std::vector<double> dist(std::size_t(shape.boundary.n_points()));
              ref.sdf->evaluate(shape.boundary.points, dist);
              double gap = 0;
              for (double x : dist) gap = std::max(gap, std::abs(x));
              double pd = 0;
              for (int k = 0; k < d; ++k)
                pd += std::pow(shape.dirichlet_center[std::size_t(k)] -
                                   ref.record["dirichlet_center"][std::size_t(k)].get<double>(), 2);
              r["boundary_gap"] = gap;
              r["dirichlet_center_offset"] = std::sqrt(pd);
            }
            const auto at_ref = at_reference(shape, solved, ref, d);
            json per = json::array();
            std::vector<double> l2s, h1s, aes, secs, cpus, sol;
            int n_ok = 0;
            for (std::size_t l = 0; l < cases.size(); ++l) {
              const auto& lo = solved.loads[l];
              json lj{{"converged", lo.converged}, {"reason", lo.reason},      {"alpha", num(lo.alpha)},
                      {"max_u", num(lo.max_u)},    {"seconds", num(lo.seconds)}, {"seconds_all", lo.seconds_all},
                      {"cpu_seconds", num(lo.cpu_seconds)}, {"cpu_seconds_all", lo.cpu_seconds_all},
                      {"newton", lo.newton},       {"solves", lo.solves},      {"failed_increments", lo.failed_increments}};
              if (lo.converged) {
                ++n_ok;
                const double e2 = ref.norms->rel_l2(ref.u[l], at_ref[l], d);
                const double e1 = ref.norms->rel_h1(ref.u[l], at_ref[l], d);
                const double ea = std::abs(lo.alpha - ref.alpha[l]) / ref.alpha[l];
                lj["rel_l2"] = num(e2);
                lj["rel_h1"] = num(e1);
                lj["alpha_err"] = num(ea);
                lj["max_u_err"] = num(std::abs(lo.max_u / cases[l].target - 1.0));
                l2s.push_back(e2), h1s.push_back(e1), aes.push_back(ea);
                same_load.push_back({sc["results"].size(), l, lo.alpha, at_ref[l]});
                const bool is_tight = s.group == "tolerance" && s.baseline_discretisation;
                if (is_tight) tight_u[l] = lo.u;
                if (s.baseline_discretisation && !is_tight && tight_u[l].size() == lo.u.size()) {
                  const double se = rel_l2_diff(lo.u, tight_u[l], tight_u[l], d);
                  lj["solver_l2"] = num(se);
                  sol.push_back(se);
                }
                if (!a.dump.empty() && !dumped && s.group == "mesh" && s.degree == 1) {
                  json dj{{"dim", d},
                          {"setting", s.name},
                          {"nodes", ref.nodes},
                          {"cells", ref.cells},
                          {"nodes_per_cell", ref.nodes_per_cell},
                          {"u_ref", ref.u[l]},
                          {"u_hat", at_ref[l]},
                          {"rel_l2", e2},
                          {"rel_h1", e1}};
                  hs::study::write_json_atomic(a.dump, dj, "--dump", 1);
                  dumped = true;
                }
              }
              secs.push_back(lo.seconds);
              cpus.push_back(lo.cpu_seconds);
              per.push_back(lj);
            }
            r["loads"] = per;
            const double amort = (shapes.seconds(s.h, s.graded) + solved.seconds_setup) / cfg.loads.count;
            r["summary"] = {{"loads", int(cases.size())},
                            {"converged", n_ok},
                            {"rel_l2", num(n_ok == int(cases.size()) ? mean_of(l2s) : NAN)},
                            {"rel_h1", num(n_ok == int(cases.size()) ? mean_of(h1s) : NAN)},
                            {"alpha_err", num(n_ok == int(cases.size()) ? mean_of(aes) : NAN)},
                            {"solver_l2", num(mean_of(sol))},
                            {"seconds_per_load", num(mean_of(secs))},
                            {"cpu_seconds_per_load", num(mean_of(cpus))},
                            {"seconds_per_load_amortised", num(mean_of(secs) + amort)}};
            std::cerr << fmt::format("[study] {}: {:<34} {:>8} DoFs  {:>9}/load  rel L2 {:.2e}  H1 {:.2e}  alpha {:.2e}  "
                                     "{}/{} ok\n",
                                     spec.name, s.name, solved.dofs, fmt_s(r["summary"]["seconds_per_load"]), mean_of(l2s),
                                     mean_of(h1s), mean_of(aes), n_ok, cases.size());
          } catch (const std::exception& e) {
            r["error"] = e.what();
            r["summary"] = {{"loads", int(cases.size())}, {"converged", 0}, {"rel_l2", nullptr}, {"rel_h1", nullptr},
                            {"alpha_err", nullptr}, {"solver_l2", nullptr}, {"seconds_per_load", nullptr},
                            {"seconds_per_load_amortised", nullptr}};
            r["peak_rss_mib"] = nullptr;
            r["peak_rss_delta_mib"] = nullptr;
            std::cerr << fmt::format("[study] {}: {}: ERROR {}\n", spec.name, s.name, e.what());
          }
          sc["results"].push_back(r);
        }
        same_load_pass(sc, shapes.at(ref_h, true), cfg, cases, ref_set, ref, same_load,
                       fmt::format("s{}_", setting_counter++), d);
      } catch (const std::exception& e) {
        sc["error"] = e.what();
        std::cerr << fmt::format("[study] {}: ERROR {}\n", spec.name, e.what());
      }
      sc["seconds"] = hs::core::now_seconds() - t_scene;
      std::cerr << fmt::format("[study] {}: done in {:.1f} s (total {:.1f} s)\n", spec.name,
                               sc["seconds"].get<double>(), hs::core::now_seconds() - t_all);
      out["scenes"].push_back(sc);
      out["seconds_total"] = hs::core::now_seconds() - t_all;
      out["load_average_end"] = load_average();
      hs::study::write_json_atomic(a.out, out, "--out", 1);
    }
    print_table(std::cout, out);
    std::cout << fmt::format("\ntotal {:.1f} s on {} ({} cores, {}); load average at start {}, end {}\n",
                             out["seconds_total"].get<double>(), out["machine"]["hostname"].get<std::string>(),
                             out["machine"]["nproc"].get<long>(),
                             out["machine"].value("cpu_model", std::string("?")), out["load_average_start"].dump(),
                             out["load_average_end"].dump());
  } catch (const std::exception& e) {
    std::cerr << fmt::format("[rank 0] {}\n", e.what());
    status = 1;
  }
  return status;
}
