#pragma once
/// Reading a closed triangle surface (the boundary of a 3D shape) from a file, through gmsh.
#include <string>

#include "hypershape/geometry/boundary.hpp"

namespace hypershape::mesh {

/// Reads one closed triangulated surface from `path`: STL (ASCII or binary; extension .stl) or a
/// gmsh mesh (.msh; its 3-node triangles, and the corner nodes of 6-node ones).
///
/// Coincident points are welded (tolerance 1e-9 x the bounding-box diagonal), the points are
/// renumbered to those the triangles use (in order of first use), and all triangles are flipped
/// if the enclosed volume is negative, so the result is outward-oriented. The result must then
/// pass geometry::check_boundary.
///
/// Throws core::InputError naming `path` when the file is missing or not a regular file, has an
/// unsupported extension, cannot be read by gmsh, holds no triangles (or holds quadrangles), or
/// is not one closed, 2-manifold, consistently oriented, non-self-intersecting surface (the
/// message carries check_boundary's reason). gmsh stays usable after a failed read. Uses the
/// open GmshSession or opens one for the call; not collective (call on one rank).
geometry::Boundary read_surface_file(const std::string& path);

}  // namespace hypershape::mesh
