#pragma once
/// One random shape, from ids to a checked mesh: draw the deformation, resolve the boundary,
/// draw the Dirichlet patch on it, make the boundary conform to the patch ends, mesh, gate the
/// quality, measure. A draw that fails any check is redrawn from the next sub-seed (attempt)
/// and the failure is recorded, never dropped silently. Not collective: every rank computes
/// the same shape for the same (seed, shape id).
#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "hypershape/geometry/boundary.hpp"
#include "hypershape/geometry/metrics.hpp"
#include "hypershape/geometry/random_shape.hpp"
#include "hypershape/mesh/mesh_data.hpp"
#include "hypershape/mesh/quality.hpp"

namespace hypershape::factory {

/// A family of random shapes (the `shapes:` block of a dataset config).
struct ShapeConfig {
  std::string name;                      ///< preset name, for reports
  int dim = 2;
  std::string base = "circle";           ///< circle | sphere | file | directory
  std::string base_file;                 ///< surface file (STL / .msh) when base == file
  /// base == directory: shape i is the surface file base_files[i] (the first `count` surface
  /// files of base_dir, sorted by name; see mesh::surface_files_in), each normalised into
  /// [-1, 1]^3 and deformed by `deformation` (usually no step: the file as it is, remeshed).
  std::string base_dir;
  std::vector<std::string> base_files;
  geometry::DeformationSpec deformation;  ///< steps, velocity unit, grid resolution
  double h = 0.05;                       ///< target element size (normalised units): the
                                         ///< resolution the shape is drawn and checked at
  /// 3D: edge length of the simulation mesh when coarser than h (0: h). The accepted surface
  /// (resolved at h, necks checked at h / 4) is remeshed at mesh_h with the same clamp sphere,
  /// checked again (closed, no self-intersection, no neck thinner than the h-level threshold)
  /// and filled at mesh_h; the stored boundary is that coarser surface, the domain solved on.
  /// Lets P2 run on a coarse mesh without coarsening the family of shapes it is drawn from.
  double mesh_h = 0.0;
  /// 3D: edge length of the surface solved on and stored (0: mesh_h, as above). shapes.h keeps
  /// the surface as drawn (its detail in the stored boundary, SDF and point cloud) while the
  /// interior still grows (size_grading per unit distance) to mesh_h.
  double surface_h = 0.0;
  /// Edge length at the clamp rim (0: not refined), growing by size_grading per unit distance:
  /// the rim is where the error lives. 3D: the rim |x - p_D| = r of the remeshed surface
  /// (geometry::RemeshOptions::size). 2D: the ends of every Dirichlet region, the drawn polygon's
  /// facets split there (grade_shape: the polygon, and so the problem, unchanged).
  double rim_size = 0.0;
  double dirichlet_radius = 0.5;         ///< r of the Dirichlet patch; 0: no patch
  /// Fixed Dirichlet regions besides the drawn patch (a dataset's `dirichlet` effects): each
  /// selects boundary facets by their vertex coordinates (n_vertices x dim, row-major), as the
  /// effect marks them on the mesh. Their facets join dirichlet_facets (so the stored mask and
  /// distance and the load placements see them); a draw with no facet in some region is
  /// redrawn (stage "support"): the family is conditioned on reaching every region.
  std::vector<std::function<bool(const double* vertex_coords, int n_vertices, int dim)>> fixed_supports;
  double max_turn_deg = 15.0;            ///< 2D: largest turning angle per boundary edge
  double min_feature_fraction = 0.1;     ///< redraw if a feature is thinner than this * h
  double size_grading = 0.3;             ///< growth of the boundary size per unit length
  int max_attempts = 20;                 ///< give up (error) after this many redraws
  mesh::QualityGate quality;             ///< defaults per dimension, see quality.hpp
};

/// 3D: the surface a shape is solved on and stored with: `drawn` (resolved at h) remeshed at
/// surface_h (mesh_h when 0) with the clamp sphere |x - p_D| = dirichlet_radius, and refined to
/// rim_size at the rim; `drawn` itself when it is already that (surface_h <= h, no rim). Throws
/// what geometry::remesh_surface throws. Not collective.
geometry::Boundary solve_surface(const geometry::Boundary& drawn, const ShapeConfig& c,
                                 const std::array<double, 3>& p_d);

/// A rejected draw: which attempt, at which stage, and why.
struct RejectedDraw {
  int attempt = 0;
  std::string stage;   ///< boundary | feature | mesh | quality | support
  std::string reason;
};

/// Everything a dataset keeps about one shape.
struct ShapeSample {
  std::int64_t shape_id = 0;
  int attempt = 0;                          ///< the accepted sub-seed
  geometry::Boundary boundary;              ///< boundary point i is mesh vertex i
  mesh::MeshData mesh;
  std::array<double, 3> dirichlet_center{};  ///< p_D (on the boundary)
  double dirichlet_radius = 0.0;
  std::vector<int> dirichlet_facets;        ///< boundary facets inside the patch or a fixed region
  geometry::ShapeMetrics metrics;
  mesh::MeshQuality quality;
  std::vector<RejectedDraw> rejected;
  std::string source_file;                  ///< base == directory: its file's name (no directory)
  double seconds_draw = 0, seconds_mesh = 0, seconds_metrics = 0;
};

/// Loads the base surface of `config` normalised into [-1, 1]^3 (any units): base == file, the
/// file; base == directory, the first file (the metrics' reference, as the seed paper compares
/// its livers with the first), after reading every file of the family so that a bad one stops
/// the run before any work. nullopt for circle/sphere. Throws core::InputError naming the bad
/// file. Not collective.
std::optional<geometry::Boundary> load_base(const ShapeConfig& config);

/// The base boundary the metrics compare against: the unit circle / sphere, or the loaded
/// surface.
geometry::Boundary reference_base(const ShapeConfig& config,
                                  const std::optional<geometry::Boundary>& loaded);

/// The name (without directory) of the surface file shape `shape_id` is made of (base ==
/// directory), or "" for the other families.
std::string source_file(const ShapeConfig& config, std::int64_t shape_id);

/// 2D: the points where a Dirichlet region of `shape` ends (a boundary point on exactly one
/// Dirichlet facet), where u is singular.
std::vector<std::array<double, 2>> clamp_ends(const ShapeSample& shape);

/// 2D: `shape` meshed again, graded towards its clamp ends: the polygon's facets split (points
/// added on them, none moved) to about end_size + growth * (distance to the nearest end), at most
/// h, and the inside meshed from that boundary (mesh::mesh_boundary). The polygon, p_D and the
/// Dirichlet facets' union are unchanged: the same boundary-value problem, discretised finer
/// where its error lives (FACTS.md). Not collective. make_shape applies it for `rim_size`.
ShapeSample grade_shape(const ShapeSample& shape, double h, double end_size, double growth);

/// Draws shape `shape_id` of the family. `base` is load_base(config); a directory family reads
/// its shape's own file here. Throws std::runtime_error if max_attempts draws all fail (with
/// every reason in the message).
ShapeSample make_shape(const ShapeConfig& config, const std::optional<geometry::Boundary>& base,
                       std::uint64_t seed, std::int64_t shape_id);

}  // namespace hypershape::factory
