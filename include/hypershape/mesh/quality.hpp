#pragma once
/// Element-quality figures of a simplex mesh and a pass/fail gate on them.
#include <cstdint>
#include <span>
#include <string>

#include "hypershape/mesh/mesh_data.hpp"

namespace hypershape::mesh {

/// Worst-element figures of a mesh (all over every cell; the measures use |det J|, so an
/// inverted cell is judged on its shape and counted in n_inverted). With no cells, every figure
/// is 0.
struct MeshQuality {
  /// 2D: the smallest interior angle of any triangle; 3D: the smallest dihedral angle of any
  /// tetrahedron (degrees; 60 and 70.53 for the regular simplices).
  double min_angle_deg = 0;
  /// The smallest shape measure, 1 for the regular simplex and 0 for a degenerate one. 2D:
  /// 4 sqrt(3) area / (sum of squared edge lengths); 3D: radius ratio 3 r_in / R_circ.
  double min_shape = 0;
  double max_edge = 0;  ///< longest cell edge (length units of the mesh)
  double min_edge = 0;  ///< shortest cell edge
  /// Cells with det J <= 0 in PETSc's convention (clockwise triangles, tetrahedra with
  /// non-negative triple product (v1-v0, v2-v0, v3-v0)).
  std::int64_t n_inverted = 0;
  std::int64_t n_cells = 0;
  std::int64_t n_vertices = 0;
};

/// The figures of one simplex (see MeshQuality for their definitions).
struct SimplexQuality {
  double min_angle_deg = 0;  ///< smallest angle (2D) or dihedral angle (3D), degrees
  double shape = 0;          ///< 1 regular, 0 degenerate
  double min_edge = 0;
  double max_edge = 0;
  /// Area / volume, positive when PETSc's det J > 0 (counter-clockwise triangle, tetrahedron
  /// with negative triple product).
  double signed_measure = 0;
};

/// The figures of the simplex with vertices `x` (dim + 1 points, dim coordinates each, dim 2 or
/// 3).
SimplexQuality simplex_quality(int dim, std::span<const double> x);

/// The quality figures of `mesh` (any dimension 2 or 3). Not collective; O(cells).
MeshQuality mesh_quality(const MeshData& mesh);

/// Lower bounds a mesh must reach to be used. Members default to 0 (only "has cells, none
/// inverted"); defaults(dim) gives the measured per-dimension gate.
struct QualityGate {
  double min_angle_deg = 0;  ///< bound on MeshQuality::min_angle_deg
  double min_shape = 0;      ///< bound on MeshQuality::min_shape

  /// The gate for meshes from mesh_boundary in dimension `dim`, set below what it reached on
  /// every test shape (so a failure means a bad boundary, not bad luck):
  ///  - 2D: min angle 18 deg, shape 0.5. Measured 25.7-43.9 deg / 0.65-0.88 on stars (smooth
  ///    and sharp, 300-2000 segments) and circles, with h from 0.2x to 8x the segment length.
  ///    A polygon corner sharper than the gate fails it whatever the mesher does.
  ///  - 3D: min dihedral 8 deg, radius ratio 0.12. Measured 14.6-23.9 deg / 0.21-0.49 on
  ///    icospheres and bumped icospheres, 10.6-14.3 deg / 0.19-0.24 on a 3:1.6:1 ellipsoid
  ///    (after the sliver clean-up; gmsh alone left 1.8 deg there), h from 0.5x to 4x the surface
  ///    edges.
  static QualityGate defaults(int dim);
};

/// True if `q` has cells, none inverted, and reaches both bounds of `gate`. Otherwise false, and
/// if `reason` is not null it is set to what failed (e.g. "min angle 12.3 deg < 18 deg").
bool passes(const MeshQuality& q, const QualityGate& gate, std::string* reason = nullptr);

}  // namespace hypershape::mesh
