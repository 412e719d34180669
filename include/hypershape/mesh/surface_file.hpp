#pragma once
/// Reading a closed triangle surface (the boundary of a 3D shape) from a file, through gmsh.
#include <string>
#include <vector>

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

/// The surface files directly in directory `dir` (what read_surface_file takes: extension .stl
/// or .msh, any case; regular files or links to them; hidden names, starting with '.', are
/// skipped), as paths `dir`/NAME sorted by NAME in byte order (so liver_010 follows liver_009
/// but liver_10 precedes liver_9: number files with leading zeros). Other files are ignored.
/// Empty if there is none. Throws core::InputError naming `dir` when it does not exist, is not a
/// directory or cannot be listed. Not collective.
std::vector<std::string> surface_files_in(const std::string& dir);

}  // namespace hypershape::mesh
