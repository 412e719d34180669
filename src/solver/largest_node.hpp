#pragma once
/// The node where a displacement-like vector is largest, chosen the same on any rank count: the
/// control node of displacement control (NonlinearSolver::control_direction) and the peak of a
/// tangent mode (mode_extent).
#include <petscdm.h>

#include <cstdint>
#include <vector>

#include "hypershape/physics/space.hpp"

namespace hypershape::solver {

struct LargestNode {
  double norm2 = -1;                  ///< the largest nodal |v|^2 over all ranks
  std::int64_t canonical = -1;        ///< its node (ties: the smallest canonical id)
  const physics::Space::OwnedNode* here = nullptr;  ///< that node where this rank owns it, else null
};

/// Over the owned nodes of `space`, from `local` (the local vector's values, constrained entries
/// zero): the largest nodal |v|^2 and its node; `norms2`, if given, gets every owned node's |v|^2
/// in owned_nodes() order. Collective over `comm`.
LargestNode largest_node(const physics::Space& space, const PetscScalar* local, MPI_Comm comm,
                         std::vector<double>* norms2 = nullptr);

}  // namespace hypershape::solver
