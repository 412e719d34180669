/// Effect "pressure" with `follower: true`: a pressure p on the deformed surface,
///   f = -p n da = -p J F^-T N dA   (Nanson),
/// per unit reference area t = -p J F^-T N. On a straight (flat) facet mapped to the deformed one
/// by the facet's basis, n da = Q x_,xi dxi (2D; Q the rotation by -90 degrees, times the sign that
/// makes it outward at u = 0) or x_,xi1 x x_,xi2 dxi (3D): linear (2D) or quadratic (3D) in the
/// nodal positions x = X + u, integrated exactly by the facet rule (degree 2k + 2).
/// Its derivative, the load stiffness, is not symmetric: in 2D the block of nodes a, b is
/// p int phi_a phi_b,xi dxi Q (a skew Q), and the sum of the (a, b) block and the transposed (b, a)
/// one is p [phi_a phi_b]_ends Q: symmetric over a closed curve or with the ends held, not on part
/// of a free boundary. The problem then has no energy (Problem::conservative() is false).
/// Keys as the dead pressure's (value, region, scale); the same "pressure" channel.
#include <array>

#include "hypershape/physics/region.hpp"
#include "hypershape/physics/registry.hpp"
#include "facet_cells.hpp"

namespace hypershape::physics {

namespace {

/// d phi / d xi_k (k < dim - 1) of facet node `ends` at barycentric `bary` (xi_k = lambda_{k+1}).
void facet_basis_gradient(int degree, const std::array<int, 2>& ends, const double* bary, int dim, double* g) {
  auto d_lambda = [&](int c) {  // d phi / d lambda_c
    const int a = ends[0], b = ends[1];
    if (a == b) return c == a ? (degree == 1 ? 1.0 : 4.0 * bary[a] - 1.0) : 0.0;
    return 4.0 * ((c == a ? bary[b] : 0.0) + (c == b ? bary[a] : 0.0));
  };
  for (int k = 0; k + 1 < dim; ++k) g[k] = d_lambda(k + 1) - d_lambda(0);
}

class FollowerPressure : public Effect {
 public:
  FollowerPressure(double p, Region region, int dim) : p_(p), region_(std::move(region)), dim_(dim) {}
  std::string name() const override { return "pressure"; }
  bool has_load() const override { return true; }
  bool follower() const override { return true; }
  void setup(const Space& s) override;
  void add_load(const Space& s, PetscScalar* f) const override { add_follower_load(s, nullptr, 1.0, f); }
  void add_follower_load(const Space& s, const PetscScalar* u, double scale, PetscScalar* f) const override;
  void add_follower_jacobian(const Space& s, const PetscScalar* u, double scale, Mat J) const override;
  std::string channel() const override { return "pressure"; }
  int channel_components(int) const override { return 1; }
  bool channel_on_boundary() const override { return true; }
  void channel_value(const double* x, double* v) const override { v[0] = region_.contains(x, dim_) ? p_ : 0.0; }

 private:
  /// At facet point q of `face` (state u, null: u = 0): the basis phi, the area vector m (n da / dxi,
  /// outward) and its derivative dm_i / dx_bj = D[b][3 i + j]. Returns the weight w_q |reference facet|.
  double point(const Space& s, const detail::FacetCell& face, double sign, const PetscScalar* u, int q, double* phi,
               double* m, std::array<std::array<double, 9>, 6>& D) const;

  double p_;
  Region region_;
  int dim_;
  std::vector<detail::FacetCell> faces_;
  std::vector<double> signs_;  ///< per face: makes the area vector outward at u = 0
};

double FollowerPressure::point(const Space& s, const detail::FacetCell& face, double sign, const PetscScalar* u, int q,
                               double* phi, double* m, std::array<std::array<double, 9>, 6>& D) const {
  const FacetView& f = *face.view;
  const int dim = s.dim();
  const double* bary = s.facet_bary(q);
  double g[2][3] = {{0, 0, 0}, {0, 0, 0}}, dphi[6][2];  // g[k] = x_,xi_k
  for (int n = 0; n < f.n_nodes; ++n) {
    const auto& e = f.ends[std::size_t(n)];
    phi[n] = s.facet_basis(e, bary);
    facet_basis_gradient(s.degree(), e, bary, dim, dphi[n]);
    for (int i = 0; i < dim; ++i) {
      const double x = 0.5 * (f.x[std::size_t(e[0])][std::size_t(i)] + f.x[std::size_t(e[1])][std::size_t(i)]) +
                       (u ? PetscRealPart(u[f.offset[std::size_t(n)] + i]) : 0.0);
      for (int k = 0; k + 1 < dim; ++k) g[k][i] += dphi[n][k] * x;
    }
  }
  for (auto& Db : D) Db.fill(0.0);
  if (dim == 2) {
    m[0] = sign * g[0][1], m[1] = -sign * g[0][0];  // Q g, Q = [[0, 1], [-1, 0]]
    for (int b = 0; b < f.n_nodes; ++b) D[std::size_t(b)][1] = sign * dphi[b][0], D[std::size_t(b)][3] = -sign * dphi[b][0];
    return s.facet_qweight(q);
  }
  const double* a = g[0];
  const double* c = g[1];
  m[0] = sign * (a[1] * c[2] - a[2] * c[1]);
  m[1] = sign * (a[2] * c[0] - a[0] * c[2]);
  m[2] = sign * (a[0] * c[1] - a[1] * c[0]);
  // d(a x c) = da x c + a x dc, da = phi_b,1 e_j, dc = phi_b,2 e_j: [a]x phi_b,2 - [c]x phi_b,1.
  auto cross_matrix = [](const double* v, double w, std::array<double, 9>& M) {
    M[1] -= w * v[2], M[2] += w * v[1], M[3] += w * v[2], M[5] -= w * v[0], M[6] -= w * v[1], M[7] += w * v[0];
  };
  for (int b = 0; b < f.n_nodes; ++b) {
    cross_matrix(a, sign * dphi[b][1], D[std::size_t(b)]);
    cross_matrix(c, -sign * dphi[b][0], D[std::size_t(b)]);
  }
  return 0.5 * s.facet_qweight(q);
}

void FollowerPressure::setup(const Space& s) {
  faces_ = detail::facet_cells(s, region_.facets());
  signs_.assign(faces_.size(), 1.0);
  double phi[6], m[3];
  std::array<std::array<double, 9>, 6> D;
  for (std::size_t k = 0; k < faces_.size(); ++k) {
    point(s, faces_[k], 1.0, nullptr, 0, phi, m, D);
    double dot = 0;
    for (int i = 0; i < s.dim(); ++i) dot += m[i] * faces_[k].view->normal[std::size_t(i)];
    signs_[k] = dot < 0 ? -1.0 : 1.0;
  }
}

void FollowerPressure::add_follower_load(const Space& s, const PetscScalar* u, double scale, PetscScalar* f) const {
  const int dim = s.dim();
  double phi[6], m[3];
  std::array<std::array<double, 9>, 6> D;
  for (std::size_t k = 0; k < faces_.size(); ++k) {
    const FacetView& fv = *faces_[k].view;
    for (int q = 0; q < s.n_facet_qp(); ++q) {
      const double w = -scale * p_ * point(s, faces_[k], signs_[k], u, q, phi, m, D);
      for (int n = 0; n < fv.n_nodes; ++n)
        for (int i = 0; i < dim; ++i) f[fv.offset[std::size_t(n)] + i] += w * phi[n] * m[i];
    }
  }
}

void FollowerPressure::add_follower_jacobian(const Space& s, const PetscScalar* u, double scale, Mat J) const {
  const int dim = s.dim();
  CellMatrixAdder adder(s, J);
  std::vector<double> Kf, Ke;
  double phi[6], m[3];
  std::array<std::array<double, 9>, 6> D;
  for (std::size_t k = 0; k < faces_.size(); ++k) {
    const FacetView& fv = *faces_[k].view;
    const int nf = fv.n_nodes * dim;
    Kf.assign(std::size_t(nf * nf), 0.0);
    for (int q = 0; q < s.n_facet_qp(); ++q) {
      // The residual holds -scale f, f = -p int phi_a m: its derivative is scale p int phi_a dm/dx_b.
      const double w = scale * p_ * point(s, faces_[k], signs_[k], u, q, phi, m, D);
      for (int a = 0; a < fv.n_nodes; ++a)
        for (int b = 0; b < fv.n_nodes; ++b)
          for (int i = 0; i < dim; ++i)
            for (int j = 0; j < dim; ++j)
              Kf[std::size_t((a * dim + i) * nf + b * dim + j)] += w * phi[a] * D[std::size_t(b)][std::size_t(3 * i + j)];
    }
    detail::facet_to_cell_matrix(s, faces_[k], Kf.data(), Ke);
    adder.add(faces_[k].cell, Ke.data());
  }
}

}  // namespace

EffectPtr make_follower_pressure(double p, const Region& region, int dim) {
  return std::make_unique<FollowerPressure>(p, region, dim);
}

}  // namespace hypershape::physics
