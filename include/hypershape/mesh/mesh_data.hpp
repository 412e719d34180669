#pragma once
/// A simplex mesh as plain arrays: what gmsh produces and DMPlex consumes.
#include <array>
#include <cstdint>
#include <vector>

namespace hypershape::mesh {

/// Straight-sided simplex mesh. Cells are positively oriented in PETSc's convention
/// (det of the reference-to-physical Jacobian > 0): counter-clockwise triangles and tetrahedra
/// with (v1-v0, v2-v0, v3-v0) of negative triple product.
struct MeshData {
  int dim = 0;
  std::vector<double> coords;  ///< n_vertices * dim
  std::vector<int> cells;      ///< n_cells * (dim + 1), vertex indices into coords

  std::int64_t n_vertices() const { return dim ? std::int64_t(coords.size()) / dim : 0; }
  std::int64_t n_cells() const { return dim ? std::int64_t(cells.size()) / (dim + 1) : 0; }
};

/// The set of boundary points where the Dirichlet patch |x - center| <= radius ends. The mesher
/// puts vertices exactly on it (two points in 2D, a curve in 3D) and grades the mesh towards it.
struct ClampRegion {
  std::array<double, 3> center{};  ///< p_D
  double radius = 0.0;             ///< r
};

}  // namespace hypershape::mesh
