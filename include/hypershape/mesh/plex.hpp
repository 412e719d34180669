#pragma once
/// MeshData -> PETSc DMPlex, orientation checks and METIS-fed distribution.
#include <petscdmplex.h>

#include "hypershape/core/petsc_handle.hpp"
#include "hypershape/mesh/mesh_data.hpp"

namespace hypershape::mesh {

/// Name of the label on boundary facets (value 1), set before distribution.
inline constexpr const char* boundary_label = "boundary";

/// Builds an interpolated DMPlex on `comm` holding every cell on rank 0 (`mesh` is read on rank 0
/// only), labels its boundary facets and checks that every cell has det J > 0 (throws
/// core::InputError otherwise). Collective.
core::DMH create_plex(MPI_Comm comm, const MeshData& mesh);

/// Throws core::InputError if any cell of `dm` has det J <= 0 (reports the count). Collective.
void check_orientation(DM dm);

/// Distributes a plex built by create_plex over its communicator with a METIS partition of the
/// cell dual graph (PETSc partitioner "shell" fed by METIS; deterministic). On one rank returns
/// an empty handle. `migration` receives the point SF from the serial to the distributed points
/// (roots: serial points on rank 0). Collective.
core::DMH distribute(DM serial, core::SFH& migration);

}  // namespace hypershape::mesh
