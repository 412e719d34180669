#pragma once
/// A dataset config: which shapes, which load cases per shape, what is solved and what is
/// stored. The paper's datasets are presets (configs/presets/*.yaml, embedded in the binary);
/// a config may start from one with `preset: NAME` and override any key.
///
/// ```yaml
/// preset: random2d                # optional: start from configs/presets/random2d.yaml
/// name: random2d
/// seed: 1001                      # every random draw is a function of (seed, shape id, load id)
/// shapes:
///   count: 1000                   # (base: directory: at most, and by default, its file count)
///   dim: 2                        # 2 | 3
///   base: circle                  # circle (2D) | sphere (3D) | file (3D, + base_file: PATH)
///                                 # | directory (3D, + base_dir: DIR: shape i = i-th surface
///                                 #   file of DIR by name, .stl/.msh)
///   steps: [[0.2, 4], [0.1, 1]]   # (sigma, m) per deformation, coarse first (base: directory:
///                                 # optional, none = each file as it is)
///   velocity_unit: 0.04           # velocity std = m * velocity_unit (optional; 0.04 2D, 0.0125 3D)
///   nodes_per_sigma: 6            # velocity grid resolution (optional; 6 in 2D, 3 in 3D)
///   h: 0.04                       # element size, in the normalised box [-1, 1]^d
///   dirichlet_radius: 0.5         # r (0: no Dirichlet patch)
///   max_turn_deg: 15              # optional, 2D boundary resolution
///   min_feature_fraction: 0.1     # optional: redraw shapes with necks thinner than this * h
///   max_attempts: 20              # optional
///   quality: {min_angle_deg: 18, min_shape: 0.3}   # optional mesh gate
/// loads:                          # optional block; these are the defaults
///   count: 50                     # load cases per shape
///   gamma: 0.2                    # traction width (paper: 0.2 in 2D, 0.1 in 3D)
///   target: [0.1, 0.5]            # max|u| range, covered by stratified sampling
/// material: {E: 500, nu: 0.49}    # compressible Neo-Hookean (appendix A)
///                                 # material, loads.gamma and shapes.dirichlet_radius are
///                                 # shorthands of this scene (the paper's three effects):
/// effects:                        # optional, instead of the shorthands: a scene's effects
///   neo_hookean: {E: {uniform: [400, 600], sample: shape}, nu: 0.49}
///   dirichlet_patch: {radius: 0.5}          # centre drawn on each shape's boundary (at most one)
///   dirichlet: [{box: [-3, -3, -0.7, 3]}]   # optional fixed regions (box or center + radius)
///   gaussian_traction:                      # a list: several tractions per load case, each
///     - {gamma: 0.2}                        # centre and direction drawn per load case
///     - {gamma: {choice: [0.1, 0.2], sample: load}}
///   body_force: {value: [0, -0.5], scale: fixed}   # not scaled by the tuned alpha
///   # or a drawn number of copies of a load: gaussian_traction: {gamma: 0.2,
///   #   count: {choice: [1, 2, 3], sample: load}}  (copy k acts where k < the count)
/// mesh: {degree: 1}               # P1 | P2; h: 3D only, optional: the mesh's edge length when
///                                 # coarser than shapes.h (the shape is drawn at shapes.h, its
///                                 # surface remeshed at h; see factory::ShapeConfig::mesh_h)
/// representations:
///   point_cloud: true             # SDF, Dirichlet distance and traction at the mesh nodes
///   grid: true                    # SDF, Dirichlet distance, traction, displacement on a grid
///   grid_size: 128                # points per axis over [-1, 1]^d (default 128 2D, 64 3D)
/// accuracy: {rel_l2: 0.01}       # optional: the factory chooses each shape's discretisation so
///                                 # that every load case's estimate meets the bound (implies
///                                 # representations.error_estimate; see factory/accuracy.hpp);
///                                 # max_level: 2 (the ladder's last level), exceed_share: 0
///                                 # (share of a shape's load cases allowed above the bound)
/// split: {train: 0.8, val: 0.1, test: 0.1}   # by shape, deterministic
/// output: {shard_size: 8}         # shapes per HDF5 shard (the unit of work and of resume)
/// solver: {rtol: 1e-9, max_newton: 12, factor_reuse: false, krylov_budget: 0, krylov_rtol: 1e-3, max_increments: 64, target_rtol: 1e-3,
///          control: displacement, path_rtol: 0.3, newton_budget: 200, fallback: false,
///          linear: auto, linear_auto_dofs: 150000}   # the defaults; linear: auto | direct | gamg | hypre
/// petsc: {snes_monitor: ""}       # any PETSc option; the command line wins
/// ```
/// Every key is checked; errors name the file and the key path (core::InputError).
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "hypershape/factory/shape_pipeline.hpp"
#include "hypershape/physics/scene.hpp"
#include "hypershape/solver/nonlinear.hpp"

namespace hypershape::config {

struct LoadsConfig {
  int count = 50;             ///< load cases per shape
  double gamma = 0.2;         ///< width of the Gaussian traction
  double target_min = 0.1;    ///< range of the target max|u|
  double target_max = 0.5;
};

struct MaterialConfig {
  double E = 500.0;
  double nu = 0.49;
  /// neo_hookean's volumetric term: "pointwise" (the seed's) or "mean" (each cell's mean
  /// dilatation: locking-free on P2; the random3d preset's).
  std::string dilatation = "pointwise";
};

struct RepresentationsConfig {
  bool point_cloud = true;
  bool grid = true;
  int grid_size = 0;          ///< points per axis; 0 until resolved (128 in 2D, 64 in 3D)
  bool error_estimate = false;  ///< loads/error_estimate_*: each label's estimated error (costs about a solve)
};

/// `accuracy:`: datasets asked for by accuracy (issue 19). Off when rel_l2 is 0.
struct AccuracyConfig {
  double rel_l2 = 0.0;        ///< bound on each load case's estimated relative L2 error of u, in (0, 1)
  int max_level = 2;          ///< the finest level of the ladder (factory::accuracy_level), in [0, 3]
  double exceed_share = 0.0;  ///< share of a shape's load cases that may stay above the bound, in [0, 0.5]
  /// `start: rest` (the default): every re-solve from rest, jumping to the lowest level predicted
  /// to meet the bound. `coarse`: a label climbs one level at a time, and each re-solve starts
  /// from the state the level below's error estimate reached on its mesh (from rest where that
  /// fails): docs/ACCURACY.md, "A re-solve that starts where the estimate ended".
  bool start_from_coarse = false;
  /// Newton iterations a re-solve (a level above 0) may spend, as solver.newton_budget bounds a
  /// load case's solve (each try and rescue its own); 0: solver.newton_budget. A re-solve that
  /// fails only keeps the label it had, so a dataset may cap what a climb costs.
  int resolve_newton_budget = 0;
  /// false: a re-solve (a level above 0) makes one try, its branch switches included, without the
  /// solver's outer rescues (solver.retry_from_rest and solver.p1_start), which keep a load case
  /// from being lost; a re-solve that fails only keeps the label it had (docs/ACCURACY.md, "What a
  /// re-solve may cost").
  bool resolve_retries = true;
  bool enabled() const { return rel_l2 > 0; }
};

struct SplitConfig {
  double train = 0.8, val = 0.1, test = 0.1;
};

struct DatasetConfig {
  std::string source;     ///< file name, or "<default dataset>"
  std::string text;       ///< the resolved YAML (preset merged), stored with the data
  std::string preset;     ///< the preset it started from, if any
  std::string name;
  std::uint64_t seed = 0;
  std::int64_t n_shapes = 0;
  factory::ShapeConfig shapes;
  LoadsConfig loads;
  MaterialConfig material;  ///< the shorthand (also set from a fixed neo_hookean of `scene`)
  /// What is solved: the config's effects, or the scene the shorthands stand for. The factory
  /// draws dirichlet_patch.center per shape and gaussian_traction center/direction per load case.
  physics::SceneSpec scene;
  bool scene_given = false;  ///< `effects:` was written (else: the shorthands)
  int degree = 1;
  int quadrature = 0;  ///< mesh.quadrature: exactness of the cell rule; 0: 2 * degree - 1
  RepresentationsConfig representations;
  AccuracyConfig accuracy;
  SplitConfig split;
  int shard_size = 8;
  solver::SolverOptions solver;
  std::vector<std::pair<std::string, std::string>> petsc;  ///< option (with dash), value
};

/// A dataset preset embedded from configs/presets/NAME.yaml at build time.
struct Preset {
  const char* name;
  const char* directory;  ///< where the file lived (relative paths in it resolve there)
  const char* text;
};
const std::vector<Preset>& presets();

/// Parses and validates a dataset config; relative paths (base_file, base_dir) are resolved
/// against the file's directory (a preset's against configs/presets/). A base_dir is listed
/// here (it must hold enough surface files); the files themselves are read by
/// factory::load_base. Throws core::InputError.
DatasetConfig parse_dataset_file(const std::string& path);
DatasetConfig parse_dataset_text(const std::string& text, const std::string& source,
                                 const std::string& base_dir = ".");
/// The dataset's meaning: every resolved value (preset merged, defaults filled in, paths
/// absolute, PETSc options sorted) in a fixed order. Two configs that differ only in layout,
/// key order, comments or defaults written out have the same canonical text; its digest is the
/// dataset's identity (`config_hash` in shards and manifest).
std::string canonical_text(const DatasetConfig& config);
/// The embedded default dataset: a small Random2D slice (a minute on a laptop).
const char* default_dataset_text();

/// The "mini" version of a parsed config (`hypershape generate --mini`), for docs, galleries and
/// loaders: name + "_mini", at most 4 shapes in 2D and 2 in 3D, 2 load cases per shape (4 when
/// the config has a single shape), grids of 32 (2D) / 16 (3D) points per axis, shards of 2
/// shapes; everything else (family, mesh, element, effects, seed) as configured, so shape i of
/// the mini dataset is shape i of the full one. Not collective. Throws core::InputError.
DatasetConfig mini_dataset(const DatasetConfig& full);
/// The config `preset: NAME` alone (`hypershape generate --preset NAME`).
DatasetConfig preset_dataset(const std::string& name);

}  // namespace hypershape::config
