#pragma once
/// A set of random shapes on disk (HDF5), written by `hypershape shapes`. Only io/ includes
/// hdf5.h. The file appears atomically (temporary name, close, rename).
///
/// Layout (docs/FORMAT.md):
///   attributes on /: dim, seed, n_shapes, name, hypershape_version
///   /config                        string      the config file as read
///   /shapes/<id, 6 digits>/        one group per shape, attributes:
///       attempt, measure, boundary_measure, isoperimetric_ratio, hausdorff_to_base,
///       min_local_feature_size, min_exterior_gap, n_boundary_facets, n_vertices, n_cells,
///       mesh_min_angle_deg, mesh_min_shape, dirichlet_center (3), dirichlet_radius,
///       seconds_draw, seconds_mesh, seconds_metrics, n_rejected;
///       source_file (string, only for a shape made of a file of a directory family)
///     boundary/points    n x dim float64   boundary point i is mesh vertex i
///     boundary/facets    m x dim int32     segments (2D, counter-clockwise) / outward triangles
///     mesh/nodes         N x dim float64
///     mesh/cells         C x (dim+1) int64 PETSc-oriented simplices
///     dirichlet_facets   k int32           rows of boundary/facets inside the patch
///     rejected           string            one line per redrawn attempt: "attempt stage: reason"
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace hypershape::io {

/// One shape as flat arrays (what factory::ShapeSample holds, without the library types, so
/// it can travel between ranks).
struct ShapeRecord {
  std::int64_t shape_id = 0;
  int dim = 2;
  std::vector<double> boundary_points;
  std::vector<int> boundary_facets;
  std::vector<double> mesh_nodes;
  std::vector<std::int64_t> mesh_cells;
  std::vector<int> dirichlet_facets;
  std::vector<double> dirichlet_center;  ///< 3
  std::map<std::string, double> numbers;  ///< scalar attributes
  std::string rejected;                   ///< one line per redrawn attempt
  std::string source_file;                ///< the surface file it was made of (directory family), or ""
};

/// Writes all shapes to `path`. Not collective. Throws std::runtime_error on I/O failure and
/// leaves no partial file behind.
void write_shapes(const std::string& path, const std::vector<ShapeRecord>& shapes,
                  const std::string& config_text, const std::string& name, std::uint64_t seed);

/// Reads a file written by write_shapes (tests and tools).
std::vector<ShapeRecord> read_shapes(const std::string& path);

}  // namespace hypershape::io
