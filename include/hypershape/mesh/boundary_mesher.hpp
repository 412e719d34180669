#pragma once
/// Meshes the inside of a given boundary (a polygon in 2D, a closed triangle surface in 3D)
/// without touching the boundary: the shape generator has already resolved it, and it carries
/// the exact ends of the Dirichlet patch.
#include <vector>

#include "hypershape/geometry/boundary.hpp"
#include "hypershape/mesh/mesh_data.hpp"

namespace hypershape::mesh {

/// Size controls for mesh_boundary. Sizes are edge lengths, in the boundary's length units, in
/// both dimensions (interior edges average about h where the size is h; gmsh's own 3D sizes,
/// as in mesh_ball, give edges about 1.36x longer).
///
/// The wanted edge length at boundary point i is s_i = the mean length of its boundary edges,
/// or point_sizes[i] where that is smaller. Away from the boundary the size moves linearly, at
/// rate `grading` per unit distance, from the s_i towards h: points finer than h pull it down
/// around them, points coarser than h (a boundary resolved coarser than h) push it up; the
/// smaller wins where they meet. So the boundary should be resolved at the sizes wanted there
/// (the mesher cannot refine it); point_sizes only refine the inside further.
struct BoundaryMeshOptions {
  /// Edge length away from the boundary (> 0).
  double h = 0.05;
  /// Optional, one per boundary point (> 0): a smaller wanted edge length next to that point
  /// (e.g. at the ends of the Dirichlet patch). Empty: the boundary's own edge lengths.
  std::vector<double> point_sizes;
  /// Growth rate of the size away from the boundary (> 0): |d size / d distance|. Smaller is
  /// smoother and costs more elements.
  double grading = 0.3;
  /// 2D: Laplacian smoothing (gmsh). 3D: gmsh's optimiser (threshold 0.6) and then our sliver
  /// clean-up (edge removal, vertex smoothing and insertion on tetrahedra with a dihedral
  /// angle below 14 deg or radius ratio below 0.2; boundary untouched).
  bool optimize = true;
};

/// A simplex mesh of the region enclosed by `boundary`, which becomes its boundary unchanged:
///  - 2D: every polygon point is a mesh vertex and every polygon segment a mesh edge; no vertex
///    is added on or moved along the polygon. The polygon must be one closed loop.
///  - 3D: the triangles of the (closed, 2-manifold) surface are exactly the boundary faces of
///    the tetrahedral mesh; gmsh only fills the volume (classic Delaunay + optimisation). The
///    surface's quality bounds the mesh's: tetrahedra on a poor triangle are poor.
///
/// Vertex order: the boundary points come first, in their order, with their exact coordinates
/// (boundary point i is mesh vertex i), then the interior vertices; so data on boundary points
/// maps to mesh vertices by index. Cells are oriented for PETSc like mesh_disk / mesh_ball
/// (counter-clockwise triangles, tetrahedra with negative triple product).
///
/// Deterministic: the same input gives the bit-identical mesh (gmsh runs single-threaded with
/// deterministic algorithms). Not collective: call on one rank. Leaves gmsh's options as it found
/// them; opens a gmsh session for the call if none is alive (see GmshSession).
///
/// Throws std::invalid_argument for malformed input (wrong dimension, index out of range, a
/// point on no facet, duplicate points, not a single closed loop / not a closed 2-manifold,
/// h <= 0, point_sizes of the wrong length or not positive), and std::runtime_error when the
/// shape could not be meshed (gmsh error, empty mesh, boundary not reproduced exactly): the
/// caller treats the latter as "redraw this shape".
MeshData mesh_boundary(const geometry::Boundary& boundary, const BoundaryMeshOptions& options);

}  // namespace hypershape::mesh
