#pragma once
/// Which FE nodes lie on which part of the boundary: the vertices of the boundary facets and,
/// for P2, the midpoints of their edges (found through the cells' edges in VTK order), marked
/// per kind of facet (the Dirichlet patch's, the rest).
#include <cstdint>
#include <vector>

#include "hypershape/geometry/boundary.hpp"

namespace hypershape::mesh {

/// `cells`: node ids per cell in VTK order (vertices, then for P2 the edge midpoints), the
/// boundary's points being the mesh's first vertices. `dirichlet` (`neumann`) gets 1 at the
/// nodes of the facets listed in `dirichlet_facets` (of the others), 0 elsewhere; a node where
/// both meet is in both. Not collective.
void boundary_node_masks(const geometry::Boundary& b, const std::vector<int>& dirichlet_facets,
                         const std::vector<std::int64_t>& cells, int degree, std::int64_t n_nodes,
                         std::vector<std::int8_t>& dirichlet, std::vector<std::int8_t>& neumann);

}  // namespace hypershape::mesh
