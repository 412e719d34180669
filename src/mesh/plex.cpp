#include "hypershape/mesh/plex.hpp"

#include <metis.h>

#include <numeric>
#include <vector>

#include "hypershape/core/error.hpp"

namespace hypershape::mesh {

core::DMH create_plex(MPI_Comm comm, const MeshData& mesh) {
  const bool root = core::rank(comm) == 0;
  int dim = root ? mesh.dim : 0;
  MPI_Bcast(&dim, 1, MPI_INT, 0, comm);
  const PetscInt n_cells = root ? PetscInt(mesh.n_cells()) : 0;
  const PetscInt n_verts = root ? PetscInt(mesh.n_vertices()) : 0;
  std::vector<PetscInt> cells;
  if (root) cells.assign(mesh.cells.begin(), mesh.cells.end());
  core::DMH dm;
  HS_PETSC(DMPlexCreateFromCellListPetsc(comm, dim, n_cells, n_verts, dim + 1, PETSC_TRUE,
                                         cells.data(), dim,
                                         root ? mesh.coords.data() : nullptr, dm.out()));
  HS_PETSC(PetscObjectSetName((PetscObject)dm.get(), "mesh"));
  HS_PETSC(DMCreateLabel(dm, boundary_label));
  DMLabel label;
  HS_PETSC(DMGetLabel(dm, boundary_label, &label));
  HS_PETSC(DMPlexMarkBoundaryFaces(dm, 1, label));
  check_orientation(dm);
  return dm;
}

void check_orientation(DM dm) {
  PetscInt c0, c1, dim;
  HS_PETSC(DMGetDimension(dm, &dim));
  HS_PETSC(DMPlexGetHeightStratum(dm, 0, &c0, &c1));
  long n_bad = 0;
  double v0[3], J[9], invJ[9], detJ;
  for (PetscInt c = c0; c < c1; ++c) {
    HS_PETSC(DMPlexComputeCellGeometryAffineFEM(dm, c, v0, J, invJ, &detJ));
    if (!(detJ > 0)) ++n_bad;
  }
  MPI_Comm comm = PetscObjectComm((PetscObject)dm);
  MPI_Allreduce(MPI_IN_PLACE, &n_bad, 1, MPI_LONG, MPI_SUM, comm);
  if (n_bad)
    throw core::InputError("", "mesh",
                           std::to_string(n_bad) +
                               " cells have a non-positive Jacobian determinant (inverted or "
                               "degenerate cells)");
}

core::DMH distribute(DM serial, core::SFH& migration) {
  MPI_Comm comm = PetscObjectComm((PetscObject)serial);
  const int n_ranks = core::size(comm);
  if (n_ranks == 1) return {};
  // METIS on the cell dual graph, computed where the cells are (rank 0).
  PetscInt n_local, *offsets = nullptr, *adjacency = nullptr;
  IS global_numbering = nullptr;
  HS_PETSC(DMPlexCreatePartitionerGraph(serial, 0, &n_local, &offsets, &adjacency,
                                        &global_numbering));
  std::vector<PetscInt> sizes(n_ranks, 0), points;
  if (n_local > 0) {
    std::vector<idx_t> xadj(offsets, offsets + n_local + 1), adj(adjacency, adjacency + offsets[n_local]);
    std::vector<idx_t> part(n_local, 0);
    idx_t nv = n_local, ncon = 1, nparts = n_ranks, objval = 0;
    idx_t options[METIS_NOPTIONS];
    METIS_SetDefaultOptions(options);
    options[METIS_OPTION_SEED] = 0;  // deterministic partitions
    options[METIS_OPTION_NUMBERING] = 0;
    const int status = METIS_PartGraphKway(&nv, &ncon, xadj.data(), adj.data(), nullptr, nullptr,
                                           nullptr, &nparts, nullptr, nullptr, options, &objval,
                                           part.data());
    if (status != METIS_OK) throw std::runtime_error("METIS_PartGraphKway failed");
    for (auto p : part) ++sizes[p];
    std::vector<PetscInt> start(n_ranks + 1, 0);
    for (int r = 0; r < n_ranks; ++r) start[r + 1] = start[r] + sizes[r];
    points.resize(n_local);
    for (PetscInt c = 0; c < n_local; ++c) points[start[part[c]]++] = c;
  }
  HS_PETSC(PetscFree(offsets));
  HS_PETSC(PetscFree(adjacency));
  HS_PETSC(ISDestroy(&global_numbering));
  PetscPartitioner part;
  HS_PETSC(DMPlexGetPartitioner(serial, &part));
  HS_PETSC(PetscPartitionerSetType(part, PETSCPARTITIONERSHELL));
  HS_PETSC(PetscPartitionerShellSetPartition(part, n_ranks, sizes.data(),
                                             points.empty() ? nullptr : points.data()));
  core::DMH dist;
  HS_PETSC(DMPlexDistribute(serial, 0, migration.out(), dist.out()));
  if (dist) HS_PETSC(PetscObjectSetName((PetscObject)dist.get(), "mesh"));
  return dist;
}

}  // namespace hypershape::mesh
