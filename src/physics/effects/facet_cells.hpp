#pragma once
/// Boundary facets selected by a predicate, each with its support cell: what a surface term with a
/// tangent (a spring bed, a follower pressure) needs to add its facet blocks as cell matrices
/// through CellMatrixAdder (the material's pattern, global numbering and fast path).
#include <array>
#include <vector>

#include "hypershape/physics/effect.hpp"
#include "hypershape/physics/space.hpp"

namespace hypershape::physics::detail {

struct FacetCell {
  const FacetView* view;
  PetscInt cell;                 ///< the facet's (only) cell
  std::array<int, 6> cell_node;  ///< each facet node's index among the cell's nodes
};

/// The Neumann facets of `s` that `select` accepts (all when empty). Not collective.
std::vector<FacetCell> facet_cells(const Space& s, const FacetPredicate& select);

/// Scatters a facet block (facet nodes x dim, row-major, (n_nodes dim)^2) into the cell matrix Ke
/// ((n_cell_dofs)^2, zeroed here) of the facet's cell.
void facet_to_cell_matrix(const Space& s, const FacetCell& face, const double* Kf, std::vector<double>& Ke);

}  // namespace hypershape::physics::detail
