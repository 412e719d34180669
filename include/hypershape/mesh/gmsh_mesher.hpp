#pragma once
/// Meshes built in-process with the gmsh C++ API. Only this module includes gmsh.h.
#include <array>
#include <optional>
#include <vector>
#include <string>

#include "hypershape/mesh/mesh_data.hpp"

namespace hypershape::mesh {

/// gmsh::initialize/finalize as a scope guard. Create one per process before meshing; the
/// functions below create one themselves when none is alive.
class GmshSession {
 public:
  GmshSession();
  GmshSession(const GmshSession&) = delete;
  GmshSession& operator=(const GmshSession&) = delete;
  ~GmshSession();
  static bool active();
};

/// Mesh-size controls.
/// gmsh's version string (a GmshSession must be open).
std::string gmsh_version();

struct MeshOptions {
  double h = 0.05;          ///< target element size away from the clamp ends
  double clamp_size = 0.0;  ///< size at the clamp ends (0: h, no grading)
  double clamp_distance = 0.0;  ///< distance over which the size grows back to h (0: 4 h)
};

/// Unit disk centred at the origin. With `clamp`, boundary vertices sit exactly where the circle
/// meets |x - center| = radius. Not collective: call on one rank.
MeshData mesh_disk(const MeshOptions& opt, const std::optional<ClampRegion>& clamp);

/// Unit ball centred at the origin; with `clamp`, the surface mesh contains the circle where the
/// sphere meets |x - center| = radius. Not collective.
MeshData mesh_ball(const MeshOptions& opt, const std::optional<ClampRegion>& clamp);

/// The box [0, L]^dim (unstructured simplices of size h), for verification problems.
MeshData mesh_box(int dim, double length, double h);

/// The inside of a simple polygon (points in order, either orientation, not repeated at the
/// end) with straight edges; every point is a mesh vertex; element size h. Not collective.
/// Throws std::invalid_argument for fewer than 3 points or h <= 0, std::runtime_error if gmsh
/// fails (e.g. a self-intersecting polygon).
MeshData mesh_polygon(const std::vector<std::array<double, 2>>& points, double h);

/// Reads a gmsh .msh file (its highest-dimensional simplices). Throws core::InputError naming
/// `path` if the file is missing, unreadable or holds no triangles/tetrahedra.
MeshData read_mesh_file(const std::string& path);

}  // namespace hypershape::mesh
