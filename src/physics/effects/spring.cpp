/// Effect "spring": an elastic (Robin, Winkler) foundation on a boundary region, the stored energy
///   E_s(u) = 1/2 int_Gamma k_n (u.N)^2 + k_t |u - (u.N) N|^2 dS_0
/// (N: the outward unit normal of the reference configuration; per unit reference area). Its
/// residual K u and tangent K are constant in u: a linear spring bed, the same at any strain.
/// Keys: stiffness (k_n = k_t = k), or normal_stiffness and/or tangential_stiffness (each >= 0,
/// default 0; not both forms); the region (region.hpp, default the whole Neumann boundary).
/// Not a material: a scene still needs one. With k_n, k_t > 0 on a region that is not a line it
/// removes the rigid modes on its own, so it counts as a support.
#include <petscdmplex.h>

#include <algorithm>
#include <array>

#include "hypershape/core/error.hpp"
#include "hypershape/physics/registry.hpp"
#include "facet_cells.hpp"

namespace hypershape::physics {

namespace {

class Spring : public Effect {
 public:
  Spring(double kn, double kt, FacetPredicate select) : kn_(kn), kt_(kt), select_(std::move(select)) {}
  std::string name() const override { return "spring"; }
  bool is_material() const override { return false; }
  bool is_support() const override { return true; }
  bool has_energy() const override { return true; }
  void setup(const Space& s) override;
  bool add_energy(const Space& s, const PetscScalar* u, double& energy) const override;
  bool add_residual(const Space& s, const PetscScalar* u, PetscScalar* r) const override;
  bool add_jacobian(const Space& s, const PetscScalar* u, Mat J) const override;

 private:
  /// A selected facet: its view, the support cell and each facet node's index in the cell.
  using Face = detail::FacetCell;
  /// The 3x3 (dim used) spring tensor k_n N N^T + k_t (I - N N^T) of a facet.
  std::array<double, 9> tensor(const FacetView& f, int dim) const;
  /// M_ab = int N_a N_b dS_0 over the facet (the facet rule), n_nodes x n_nodes row-major.
  std::array<double, 36> facet_mass(const Space& s, const FacetView& f) const;
  /// Calls term(face, a, i, b, j, c) for every entry c = M_ab K_ij of every facet's block
  /// (nodes a, b of the facet, components i, j).
  template <class Term>
  void for_each_entry(const Space& s, Term&& term) const {
    const int dim = s.dim();
    for (const Face& face : faces_) {
      const FacetView& f = *face.view;
      const auto k = tensor(f, dim);
      const auto m = facet_mass(s, f);
      for (int a = 0; a < f.n_nodes; ++a)
        for (int b = 0; b < f.n_nodes; ++b)
          for (int i = 0; i < dim; ++i)
            for (int j = 0; j < dim; ++j) term(face, a, i, b, j, m[std::size_t(6 * a + b)] * k[std::size_t(3 * i + j)]);
    }
  }

  double kn_, kt_;
  FacetPredicate select_;
  std::vector<Face> faces_;
};

std::array<double, 9> Spring::tensor(const FacetView& f, int dim) const {
  std::array<double, 9> k{};
  for (int i = 0; i < dim; ++i)
    for (int j = 0; j < dim; ++j)
      k[std::size_t(3 * i + j)] = (kn_ - kt_) * f.normal[std::size_t(i)] * f.normal[std::size_t(j)] + (i == j ? kt_ : 0.0);
  return k;
}

std::array<double, 36> Spring::facet_mass(const Space& s, const FacetView& f) const {
  std::array<double, 36> m{};
  const double measure = Space::facet_measure(f, s.dim());
  for (int q = 0; q < s.n_facet_qp(); ++q) {
    const double* bary = s.facet_bary(q);
    const double w = s.facet_qweight(q) * measure;
    for (int a = 0; a < f.n_nodes; ++a)
      for (int b = 0; b < f.n_nodes; ++b)
        m[std::size_t(6 * a + b)] += w * s.facet_basis(f.ends[a], bary) * s.facet_basis(f.ends[b], bary);
  }
  return m;
}

void Spring::setup(const Space& s) { faces_ = detail::facet_cells(s, select_); }

bool Spring::add_energy(const Space& s, const PetscScalar* u, double& energy) const {
  for_each_entry(s, [&](const Face& face, int a, int i, int b, int j, double c) {
    const FacetView& f = *face.view;
    energy += 0.5 * c * PetscRealPart(u[f.offset[std::size_t(a)] + i]) * PetscRealPart(u[f.offset[std::size_t(b)] + j]);
  });
  return true;
}

bool Spring::add_residual(const Space& s, const PetscScalar* u, PetscScalar* r) const {
  for_each_entry(s, [&](const Face& face, int a, int i, int b, int j, double c) {
    const FacetView& f = *face.view;
    r[f.offset[std::size_t(a)] + i] += c * u[f.offset[std::size_t(b)] + j];
  });
  return true;
}

bool Spring::add_jacobian(const Space& s, const PetscScalar*, Mat J) const {
  // Each facet's block goes in as a (mostly zero) matrix of its support cell, so that the
  // spring uses the same pattern, global numbering and fast path as the material.
  const int dim = s.dim(), nd = s.n_cell_dofs();
  CellMatrixAdder adder(s, J);
  std::vector<double> Ke(std::size_t(nd * nd));
  const Face* current = nullptr;
  auto flush = [&] {
    if (current) adder.add(current->cell, Ke.data());
  };
  for_each_entry(s, [&](const Face& face, int a, int i, int b, int j, double c) {
    if (&face != current) {
      flush();
      current = &face;
      std::fill(Ke.begin(), Ke.end(), 0.0);
    }
    Ke[std::size_t((face.cell_node[std::size_t(a)] * dim + i) * nd + face.cell_node[std::size_t(b)] * dim + j)] += c;
  });
  flush();
  return true;
}

/// k_n, k_t from the keys (see the file comment); errors name the key.
std::pair<double, double> stiffnesses(const core::Params& p) {
  if (p.has("stiffness")) {
    if (p.has("normal_stiffness") || p.has("tangential_stiffness"))
      p.fail("stiffness", "give stiffness or normal_stiffness/tangential_stiffness, not both");
    const double k = p.number_in("stiffness", 0.0, 1e300, true);
    return {k, k};
  }
  const double kn = p.has("normal_stiffness") ? p.number_in("normal_stiffness", 0.0, 1e300) : 0.0;
  const double kt = p.has("tangential_stiffness") ? p.number_in("tangential_stiffness", 0.0, 1e300) : 0.0;
  if (!(kn + kt > 0))
    p.fail("stiffness", "a spring needs stiffness > 0, or normal_stiffness and/or tangential_stiffness > 0");
  return {kn, kt};
}

}  // namespace

EffectPtr make_spring(double normal_stiffness, double tangential_stiffness, const Region& region) {
  return std::make_unique<Spring>(normal_stiffness, tangential_stiffness, region.facets());
}

void register_spring() {
  register_effect(
      "spring",
      [](const core::Params& p, int dim) {
        const auto [kn, kt] = stiffnesses(p);
        return make_spring(kn, kt, Region::from_params(p, dim, false));
      },
      std::string("elastic (Robin) foundation, energy 1/2 int k_n (u.N)^2 + k_t |u_tangential|^2 dS_0; keys: "
                  "stiffness (k_n = k_t) or normal_stiffness / tangential_stiffness (>= 0), ") +
          region_help());
}

}  // namespace hypershape::physics
