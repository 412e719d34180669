#pragma once
/// The pieces of the accuracy study (src/study/accuracy*.cpp); internal to the library.
#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "hypershape/config/dataset.hpp"
#include "hypershape/factory/load_cases.hpp"
#include "hypershape/factory/shape_pipeline.hpp"
#include "hypershape/geometry/distance.hpp"
#include "hypershape/physics/problem.hpp"
#include "hypershape/sampling/field_error.hpp"
#include "hypershape/solver/nonlinear.hpp"
#include "hypershape/study/accuracy.hpp"

namespace hypershape::study::accuracy {

using json = nlohmann::json;
using PetscOptionList = std::vector<std::pair<std::string, std::string>>;

enum class SceneKind { disk, ball, random2d, random3d };

struct SceneSpec {
  std::string name;
  std::string preset;  ///< E, nu, r, gamma, h, degree, solver defaults (and the shape family)
  SceneKind kind = SceneKind::random2d;
  std::int64_t shape_id = 0;
};

/// The study's scenes: the disk, Random2D shapes 0 and 1, OODRandom2D and EasyRandom2D shape 0,
/// the ball, Random3D shape 0 (the accuracy study's and the error estimate's validation).
const std::vector<SceneSpec>& study_scenes();

/// One way of solving the sample problem.
struct Setting {
  std::string name, group;
  int degree = 1;
  double h = 0;
  int quadrature = 0;  ///< 0: the space's default (2 degree - 1)
  solver::SolverOptions opt;
  PetscOptionList petsc;  ///< without prefix
  bool linear_model = false;
  bool auto_solver = false;  ///< beyond kAutoMumpsDofs unknowns: MUMPS LDL^T (see solve_setting)
  bool graded = false;       ///< on the reference's (graded) mesh of the disk
  /// Diagnostic (2D): the load (p_N and g) rotated by this angle about the origin; on the disk
  /// that is the problem with p_D moved by the same arc length relative to the load.
  double load_rotation = 0;
  bool is_default = false;
  bool baseline_discretisation = false;  ///< same (h, degree, quadrature) as the baseline
};

std::string fmt_g(double v);

// ---- scenes and shapes (accuracy_shapes.cpp) ----

/// The scene's preset, with the --override YAML (dataset-config keys) merged over it.
config::DatasetConfig scene_config(const SceneSpec& s, const std::string& override_yaml);
/// The preset's element size: shapes.h, or the coarser mesh.h of the 3D presets.
double preset_mesh_h(const config::DatasetConfig& cfg);

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
  ShapeCache(SceneKind kind, factory::ShapeConfig c, std::uint64_t seed, std::int64_t id, double finest_h)
      : kind_(kind), config_(std::move(c)), seed_(seed), id_(id), finest_h_(finest_h) {}
  /// The shape resolved at h; `graded`: the reference variant (the disk's polygon graded
  /// towards the patch ends; the same as the plain one for the other kinds).
  const factory::ShapeSample& at(double h, bool graded = false);
  /// Seconds it took to build the shape at h (NaN if not built).
  double seconds(double h, bool graded = false) const;
  void set_grading(double grade_end) { grade_end_ = grade_end; }

 private:
  /// Mesh, patch facets and bookkeeping of a boundary resolved at h.
  factory::ShapeSample finish(geometry::Boundary b, const std::array<double, 3>& p_d, double h) const;
  factory::ShapeSample build(double h, bool graded);
  factory::ShapeSample build_disk(double h, bool graded) const;
  factory::ShapeSample build_ball(double h);
  factory::ShapeSample build_random3d(double h);

  SceneKind kind_;
  factory::ShapeConfig config_;
  std::uint64_t seed_;
  std::int64_t id_;
  double finest_h_;
  std::optional<geometry::Boundary> sphere_;
  std::optional<int> attempt_;  ///< random3d: the draw accepted at the first h built
  double grade_end_ = 1.0;
  std::vector<std::pair<std::pair<double, bool>, std::unique_ptr<factory::ShapeSample>>> shapes_;
  std::vector<std::pair<std::pair<double, bool>, double>> seconds_;
};

/// The shape at another h must come from the same random draw (sub-seed) as the baseline's.
void check_same_draw(const factory::ShapeSample& shape, const factory::ShapeSample& base, double h);

// ---- solving one setting (accuracy_solve.cpp) ----

struct LoadOutcome {
  bool converged = false;
  std::string reason;
  double alpha = NAN, max_u = NAN, seconds = NAN;
  std::vector<double> seconds_all;
  std::vector<double> cpu_seconds_all;  ///< process CPU time of the same runs
  double cpu_seconds = NAN;
  int newton = 0, solves = 0, failed_increments = 0;
  std::vector<int> newton_all;  ///< Newton iterations of each repeat (equal: each from the same hint)
  std::vector<double> u;  ///< gathered nodal displacement (canonical order)
};

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

PetscOptionList mumps_cholesky();

/// Called after load case `l` of a setting was solved (at its target), with the solver still
/// at that state: the same-load pass continues the reference from there.
using AfterLoad = std::function<void(std::size_t l, solver::NonlinearSolver&, const physics::Problem&)>;

/// Builds the problem of `shape` from the dataset's scene (factory::make_shape_problem) and
/// solves every load case with setting `s`, `repeats` times each (fewer when a run takes longer
/// than `repeat_above` seconds). Never throws for a numerical failure.
SolvedSetting solve_setting(const factory::ShapeSample& shape, const config::DatasetConfig& cfg,
                            const std::vector<factory::LoadCase>& cases, const Setting& s, int repeats,
                            double repeat_above, const std::string& prefix, bool verbose,
                            const AfterLoad& after_load = {});

// ---- the reference (accuracy_reference.cpp) ----

/// What every setting is compared with: the finest solve of one scene, at its nodes.
struct Reference {
  double h = 0;
  std::vector<double> nodes;
  std::vector<std::int64_t> cells;
  int nodes_per_cell = 0;
  std::unique_ptr<sampling::NodalNorms> norms;
  std::unique_ptr<geometry::SignedDistance> sdf;  ///< of the reference boundary
  std::vector<std::vector<double>> u;             ///< per load case
  std::vector<double> alpha;
  json record;
};

/// Evaluates the field of a solved setting at the reference's nodes.
std::vector<std::vector<double>> at_reference(const factory::ShapeSample& shape, const SolvedSetting& s,
                                              const Reference& ref, int d);
double rel_l2_diff(const std::vector<double>& a, const std::vector<double>& b, const std::vector<double>& ref, int d);

/// One scene as the study runs it: its config, shapes and load cases.
struct Scene {
  const AccuracyOptions& a;
  const SceneSpec& spec;
  config::DatasetConfig cfg;
  int d = 2;
  double ref_h = 0;
  int n_levels = 2;
  std::unique_ptr<ShapeCache> shapes;
  const factory::ShapeSample* base_shape = nullptr;
  std::vector<factory::LoadCase> cases;
  int& setting_counter;  ///< numbers the PETSc option prefixes of the whole run
};

/// The reference's setting: P2, rtol 1e-10, target_rtol 1e-6, MUMPS LDL^T.
Setting reference_setting(const Scene& s);
/// Solves the reference and its ladder (h_ref, 2 h_ref[, 4 h_ref]), estimates its own error by
/// Richardson extrapolation, and returns it with its JSON record.
Reference build_reference(Scene& s, const Setting& ref_set);

/// One setting's answer to one load case, evaluated at the reference's nodes.
struct SameLoad {
  std::size_t result = 0, load = 0;  ///< index in the scene's results, load case
  double alpha = NAN;
  std::vector<double> u;
};

/// The error of a sample as a training pair (see accuracy_same_load.cpp): adds
/// "same_load_rel_l2" / "same_load_rel_h1" to sc["results"] and sc["same_load_pass"].
void same_load_pass(json& sc, const factory::ShapeSample& ref_shape, const config::DatasetConfig& cfg,
                    const std::vector<factory::LoadCase>& cases, const Setting& ref_set, const Reference& ref,
                    std::vector<SameLoad>& answers, const std::string& prefix, int d);

// ---- settings and output (accuracy_settings.cpp, accuracy_report.cpp) ----

/// The settings of one scene: the baseline, the h x degree grid, one knob at a time.
std::vector<Setting> make_settings(int dim, const AccuracyOptions& a, const config::DatasetConfig& cfg,
                                   double ref_h, SceneKind scene_kind);
json setting_json(const Setting& s);

/// Settings measured against the reference (accuracy_settings.cpp's results loop).
void run_settings(Scene& s, const std::vector<Setting>& settings, const Reference& ref, json& sc,
                  std::vector<SameLoad>& same_load);

std::string fmt_s(const json& v);
void print_table(std::ostream& os, const json& out);

}  // namespace hypershape::study::accuracy
