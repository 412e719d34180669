#pragma once
/// The node layout of the project's cells, in one place: VTK's (and XDMF's) linear and
/// quadratic triangles and tetrahedra. Vertices 0..dim first; a quadratic cell then has one
/// node per edge, at local index dim + 1 + e for edge e of `edges(dim)`:
///   triangle:    m01 m12 m20
///   tetrahedron: m01 m12 m20 m03 m13 m23
/// The stored meshes (`cells` of a shard), the sampler, the field norms and the node masks all
/// read cells in this order.
#include <span>
#include <stdexcept>
#include <utility>

namespace hypershape::mesh {

using Edge = std::pair<int, int>;

inline constexpr Edge kTriangleEdges[3] = {{0, 1}, {1, 2}, {2, 0}};
inline constexpr Edge kTetrahedronEdges[6] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};

/// The edges of the simplex of dimension `dim` (2 or 3), in node order.
constexpr std::span<const Edge> edges(int dim) {
  if (dim == 2) return kTriangleEdges;
  return kTetrahedronEdges;
}

/// Nodes per cell: P1 dim + 1, P2 (dim + 1) + edges.
constexpr int nodes_per_cell(int dim, int degree) {
  return degree == 1 ? dim + 1 : dim + 1 + int(edges(dim).size());
}

/// Local node at the midpoint of the edge between local vertices a != b (either orientation).
constexpr int edge_node(int dim, int a, int b) {
  const auto e = edges(dim);
  for (int i = 0; i < int(e.size()); ++i)
    if ((e[i].first == a && e[i].second == b) || (e[i].first == b && e[i].second == a)) return dim + 1 + i;
  throw std::invalid_argument("edge_node: no edge between these local vertices");
}

static_assert(edge_node(2, 2, 0) == 5 && edge_node(3, 1, 3) == 8 && edge_node(3, 2, 0) == 6);
static_assert(nodes_per_cell(2, 2) == 6 && nodes_per_cell(3, 2) == 10 && nodes_per_cell(3, 1) == 4);

}  // namespace hypershape::mesh
