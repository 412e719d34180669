#include "hypershape/mesh/boundary_nodes.hpp"

#include <algorithm>
#include <map>
#include <utility>

#include "hypershape/mesh/reference_cell.hpp"

namespace hypershape::mesh {

void boundary_node_masks(const geometry::Boundary& b, const std::vector<int>& dirichlet_facets,
                         const std::vector<std::int64_t>& cells, int degree, std::int64_t n_nodes,
                         std::vector<std::int8_t>& dirichlet, std::vector<std::int8_t>& neumann) {
  const int d = b.dim;
  dirichlet.assign(std::size_t(n_nodes), 0);
  neumann.assign(std::size_t(n_nodes), 0);
  std::map<std::pair<std::int64_t, std::int64_t>, std::int64_t> midpoint;
  if (degree == 2) {
    const auto per = std::size_t(nodes_per_cell(d, 2));
    const auto cell_edges = edges(d);
    for (std::size_t c = 0; c + per <= cells.size(); c += per)
      for (std::size_t e = 0; e < cell_edges.size(); ++e) {
        auto a = cells[c + std::size_t(cell_edges[e].first)], z = cells[c + std::size_t(cell_edges[e].second)];
        midpoint[{std::min(a, z), std::max(a, z)}] = cells[c + std::size_t(d + 1) + e];
      }
  }
  std::vector<std::uint8_t> is_dirichlet(std::size_t(b.n_facets()), 0);
  for (int f : dirichlet_facets) is_dirichlet[std::size_t(f)] = 1;
  for (std::int64_t f = 0; f < b.n_facets(); ++f) {
    auto& mask = is_dirichlet[std::size_t(f)] ? dirichlet : neumann;
    const auto v = b.facet(f);
    for (int a = 0; a < d; ++a) mask[std::size_t(v[a])] = 1;
    if (degree == 2)
      for (int a = 0; a < d; ++a)
        for (int z = a + 1; z < d; ++z) {
          const std::int64_t p = v[a], q = v[z];
          auto it = midpoint.find({std::min(p, q), std::max(p, q)});
          if (it != midpoint.end()) mask[std::size_t(it->second)] = 1;
        }
  }
}

}  // namespace hypershape::mesh
