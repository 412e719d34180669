#pragma once
/// Uniform ("red") refinement of a simplex mesh: every triangle into 4, every tetrahedron into 8
/// (the inner octahedron cut along its shortest diagonal). The fine mesh is nested in the coarse
/// one, so a P1 or P2 field of the coarse mesh is exactly a field of the fine one (same degree):
/// the two-level error estimate (solver/error_estimate.hpp) and its validation rely on that.
#include <array>
#include <cstdint>
#include <vector>

#include "hypershape/mesh/mesh_data.hpp"

namespace hypershape::mesh {

struct RefinedMesh {
  MeshData mesh;  ///< the fine mesh: coarse vertices first (same ids), then one per coarse edge
  /// Coarse cell of each fine cell.
  std::vector<std::int64_t> parent;
  /// Barycentric coordinates, in the parent, of each fine cell's vertices:
  /// n_fine_cells x (dim + 1) x (dim + 1), vertex-major.
  std::vector<double> bary;
  std::int64_t n_coarse_vertices = 0;
  std::vector<int> coarse_cells;  ///< the coarse mesh's cells (the order `bary` refers to)
};

/// Refines `coarse` once; children keep the parent's orientation (det sign). Not collective.
RefinedMesh refine_uniform(const MeshData& coarse);

}  // namespace hypershape::mesh
