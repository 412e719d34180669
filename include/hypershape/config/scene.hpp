#pragma once
/// A scene file fixes every choice of one solve: base shape, mesh, effects, load, solver.
///
/// ```yaml
/// geometry: {base: circle}            # circle (2D) | sphere (3D) | file (+ file: PATH.msh)
///                                     # or {polygon: [[x, y], ...]} (2D, straight edges)
/// mesh: {h: 0.05, degree: 1, clamp_refinement: 0.25}
/// effects:                           # a list for an effect that appears several times:
///   neo_hookean: {E: 500, nu: 0.49}   #   gaussian_traction: [{...}, {...}]
///                                     # loads take scale: alpha (default) | fixed
///   dirichlet_patch: {center: [1, 0], radius: 0.5}
///   gaussian_traction: {center: [-1, 0], direction: [0, 1], gamma: 0.2}
/// load: {target: 0.3}                 # or {alpha: 10}
/// solver: {rtol: 1e-9, max_newton: 12, target_rtol: 1e-3, control: displacement, linear: auto}
/// petsc: {snes_monitor: ""}           # any PETSc options, without the leading dash
/// ```
/// Every key is checked: unknown keys, wrong types and out-of-range values throw
/// core::InputError naming the file and the key path.
#include <array>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "hypershape/core/params.hpp"
#include "hypershape/physics/scene.hpp"
#include "hypershape/physics/space.hpp"
#include "hypershape/solver/nonlinear.hpp"

namespace hypershape::config {

struct Scene {
  std::string source;      ///< file name, or "<default scene>"
  std::string text;        ///< the YAML as read (stored with the results)
  std::string base;        ///< circle | sphere | file | polygon
  std::vector<std::array<double, 2>> polygon;  ///< base == polygon: its points in order
  std::string mesh_file;   ///< resolved path when base == file
  int dim = 2;             ///< 0 until known for base == file
  double h = 0.05;
  int degree = 1;
  double clamp_refinement = 0.25;
  /// 3D sphere: the datasets' discretisation keys (factory::ShapeConfig::surface_h, rim_size).
  /// With either set, the ball is meshed as the factory meshes a shape (a fine icosphere
  /// remeshed at surface_h, h when 0, with the clamp curve and the rim refinement, then filled
  /// up to h) instead of by gmsh's sphere with clamp_refinement. 2D circle: rim_size is the size
  /// at the patch ends (instead of h * clamp_refinement).
  double surface_h = 0, rim_size = 0;
  physics::SceneSpec effects;  ///< in file order; numbers only (no draws in a scene file)
  std::optional<double> alpha, target;
  solver::SolverOptions solver;
  std::vector<std::pair<std::string, std::string>> petsc;  ///< option (with dash), value
};

/// Parses and validates a scene (everything but the effects' own keys, which are checked when
/// the effects are built). Throws core::InputError.
Scene parse_scene_file(const std::string& path);
Scene parse_scene_text(const std::string& text, const std::string& source, const std::string& base_dir = ".");
/// The effects of a scene as a YAML `effects:` mapping (lists for repeated effects, draws as
/// written): stored with the data of a dataset (shard attribute "scene").
std::string effects_yaml(const physics::SceneSpec& spec);

/// The embedded default scene: the seed paper's set-up on the unit disk.
const char* default_scene_text();

}  // namespace hypershape::config
