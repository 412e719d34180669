#include "facet_cells.hpp"

#include <petscdmplex.h>

#include <algorithm>
#include <stdexcept>

#include "hypershape/core/error.hpp"

namespace hypershape::physics::detail {

std::vector<FacetCell> facet_cells(const Space& s, const FacetPredicate& select) {
  const int dim = s.dim();
  std::vector<FacetCell> out;
  for (const FacetView& f : s.neumann_facets()) {
    double x[9];
    for (int a = 0; a < f.n_vertices; ++a)
      for (int k = 0; k < dim; ++k) x[a * dim + k] = f.x[std::size_t(a)][std::size_t(k)];
    if (select && !select(x, f.n_vertices, dim)) continue;
    const PetscInt* support;
    HS_PETSC(DMPlexGetSupport(s.dm(), f.point, &support));
    FacetCell face{&f, support[0], {}};
    const PetscInt* ld = s.local_dofs(face.cell);
    for (int n = 0; n < f.n_nodes; ++n) {
      const auto it = std::find(ld, ld + s.n_cell_dofs(), f.offset[std::size_t(n)]);
      if (it == ld + s.n_cell_dofs()) throw std::logic_error("a facet node is not in its cell");
      face.cell_node[std::size_t(n)] = int(it - ld) / dim;
    }
    out.push_back(face);
  }
  return out;
}

void facet_to_cell_matrix(const Space& s, const FacetCell& face, const double* Kf, std::vector<double>& Ke) {
  const int dim = s.dim(), nd = s.n_cell_dofs(), nf = face.view->n_nodes * dim;
  Ke.assign(std::size_t(nd * nd), 0.0);
  for (int a = 0; a < face.view->n_nodes; ++a)
    for (int i = 0; i < dim; ++i)
      for (int b = 0; b < face.view->n_nodes; ++b)
        for (int j = 0; j < dim; ++j)
          Ke[std::size_t((face.cell_node[std::size_t(a)] * dim + i) * nd + face.cell_node[std::size_t(b)] * dim + j)] =
              Kf[(a * dim + i) * nf + b * dim + j];
}

}  // namespace hypershape::physics::detail
