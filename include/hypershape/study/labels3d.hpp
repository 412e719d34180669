#pragma once
/// How well a 3D label resolves its shape and its load (issue 16, part B): one load case of a
/// 3D scene (the unit ball, or Random3D shape 0, with the random3d preset's material, patch and
/// gamma) solved at a fixed traction scale alpha on many discretisations, each compared with a
/// reference on the label's nodes. Write-up: docs/ACCURACY.md ("3D labels"); driver
/// drivers/study_labels3d.cpp.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace hypershape::study::labels3d {

/// One discretisation: a surface remeshed at `surface_h` (with the clamp curve), refined where
/// RemeshOptions::size asks (at the clamp rim and/or around p_N), and a P2 volume mesh graded
/// from that surface towards `interior_h` (mesh::mesh_boundary).
struct Discretisation {
  std::string name;
  double surface_h = 0.3;   ///< edge length of the surface away from the refinements
  double interior_h = 0.3;  ///< edge length deep inside
  double rim_size = 0;      ///< edge length at the clamp rim |x - p_D| = r (0: not refined)
  double load_size = 0;     ///< edge length at p_N (0: not refined); makes the mesh per load case
  double grading = 0.3;     ///< growth of the refinements' size per unit distance
  /// A per-load-case mesh's label lives on this discretisation's mesh (the shape's stored
  /// nodes): the solution is sampled onto its vertices. Empty: on its own vertices.
  std::string label_on;
  /// The material's volumetric energy: "pointwise" (the seed's) or "mean" (neo_hookean's
  /// dilatation: mean, the P2/P0 mean-dilatation element).
  std::string dilatation = "pointwise";
  double pointwise_share = 0;  ///< with mean: neo_hookean's pointwise_share
  bool per_load() const { return load_size > 0; }
};

/// Parses "name:key=value,key=value" (keys surface_h, interior_h, h (both), rim, load, share,
/// grading, label_on, dilatation). Throws std::invalid_argument naming the bad key.
Discretisation parse_discretisation(const std::string& spec);

struct Options {
  std::string scene = "ball";  ///< ball | r3d-0
  double alpha = 5;            ///< traction scale every discretisation is solved at
  std::string reference;       ///< the discretisation the others are compared with (its name)
  std::vector<Discretisation> discretisations;  ///< the reference among them
  int loads_per_shape = 20;    ///< amortises per-shape mesh + set-up over this many load cases
  bool time_target = false;    ///< also time solve_for_target(reference max|u|) (the factory's path)
  std::string write_dir;       ///< if set: every solution as <dir>/<scene>_<name>.h5 (io::write_solution)
};

/// Solves every discretisation (one rank) and returns the results as JSON: per discretisation
/// DoFs, vertices, Newton iterations, times (mesh, set-up, solve, sampling, per load case),
/// max|u|, and against the reference on the label's vertices: rel L2 (the seed paper's nodal
/// norm and a lumped-volume-weighted one) and the relative error of max|u|.
nlohmann::json run(const Options& opt);

}  // namespace hypershape::study::labels3d
