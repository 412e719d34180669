/// Dead surface tractions on the Neumann boundary, and the effect "gaussian_traction" of the
/// seed paper (section 3.2): t(x) = alpha g phi(x - p_N) / I_N, phi(y) = exp(-|y|^2/(2 gamma^2)),
/// I_N = int_{Gamma_N} phi dS by the facet rule. alpha is the problem's load factor.
/// Keys: center (p_N), direction (g, normalised here), gamma (> 0).
#include <cmath>
#include <stdexcept>

#include "hypershape/core/error.hpp"
#include "hypershape/physics/gaussian_traction.hpp"
#include "hypershape/physics/registry.hpp"
#include "hypershape/physics/surface_load.hpp"

namespace hypershape::physics {

namespace {

/// Integrates `fn(x, weight)` over the selected Neumann facets with the facet rule.
template <class Fn>
void for_each_facet_point(const Space& s, const FacetPredicate& select, Fn&& fn) {
  const int dim = s.dim();
  for (const FacetView& f : s.neumann_facets()) {
    if (select) {
      double x[9];
      for (int a = 0; a < f.n_vertices; ++a)
        for (int k = 0; k < dim; ++k) x[a * dim + k] = f.x[a][k];
      if (!select(x, f.n_vertices, dim)) continue;
    }
    const double measure = Space::facet_measure(f, dim);
    for (int q = 0; q < s.n_facet_qp(); ++q) {
      const double* bary = s.facet_bary(q);
      double x[3] = {0, 0, 0};
      for (int a = 0; a < f.n_vertices; ++a)
        for (int k = 0; k < dim; ++k) x[k] += bary[a] * f.x[a][k];
      fn(f, bary, x, s.facet_qweight(q) * measure);
    }
  }
}

/// Adds int t . N_a dS to f for the traction `traction(facet, x, t)` on the selected facets.
template <class Traction>
void add_facet_load(const Space& s, const FacetPredicate& select, Traction&& traction, PetscScalar* f) {
  const int dim = s.dim();
  for_each_facet_point(s, select, [&](const FacetView& fv, const double* bary, const double* x, double w) {
    double t[3] = {0, 0, 0};
    traction(fv, x, t);
    for (int n = 0; n < fv.n_nodes; ++n) {
      const double wn = w * s.facet_basis(fv.ends[n], bary);
      for (int i = 0; i < dim; ++i) f[fv.offset[n] + i] += wn * t[i];
    }
  });
}

}  // namespace

void SurfaceLoad::add_load(const Space& s, PetscScalar* f) const {
  add_facet_load(s, select_, [&](const FacetView& fv, const double* x, double* t) { load_(x, fv.normal.data(), t); }, f);
}

EffectPtr make_surface_traction(VectorFunction traction, FacetPredicate select) {
  return std::make_unique<SurfaceLoad>(
      "surface_traction", [t = std::move(traction)](const double* x, const double*, double* v) { t(x, v); },
      std::move(select));
}

GaussianTraction::GaussianTraction(std::vector<double> center, std::vector<double> direction,
                                   double gamma)
    : gamma_(gamma) {
  set(std::move(center), std::move(direction));
}

void GaussianTraction::set(std::vector<double> center, std::vector<double> direction) {
  double n = 0;
  for (double v : direction) n += v * v;
  n = std::sqrt(n);
  if (!(n > 0) || center.size() != direction.size())
    throw std::invalid_argument("GaussianTraction: direction must be non-zero, of the centre's size");
  for (double& v : direction) v /= n;
  center_ = std::move(center);
  g_ = std::move(direction);
  normaliser_ = 0;
}

double GaussianTraction::phi(const double* x) const {
  double r2 = 0;
  for (int k = 0; k < dim_; ++k) r2 += (x[k] - center_[k]) * (x[k] - center_[k]);
  return std::exp(-r2 / (2.0 * gamma_ * gamma_));
}

void GaussianTraction::setup(const Space& s) {
  dim_ = s.dim();
  double integral = 0;
  for_each_facet_point(s, {}, [&](const FacetView&, const double*, const double* x, double w) {
    integral += w * phi(x);
  });
  MPI_Allreduce(MPI_IN_PLACE, &integral, 1, MPI_DOUBLE, MPI_SUM, s.comm());
  if (!(integral > 0))
    throw core::InputError("", "gaussian_traction",
                           "the Neumann boundary is empty or far from the traction centre "
                           "(int phi = 0)");
  normaliser_ = integral;
}

void GaussianTraction::value(const double* x, double* t) const {
  const double v = phi(x) / normaliser_;
  for (int i = 0; i < dim_; ++i) t[i] = g_[i] * v;
}

void GaussianTraction::add_load(const Space& s, PetscScalar* f) const {
  add_facet_load(s, {}, [&](const FacetView&, const double* x, double* t) { value(x, t); }, f);
}

EffectPtr make_gaussian_traction(const std::vector<double>& center,
                                 const std::vector<double>& direction, double gamma) {
  return std::make_unique<GaussianTraction>(center, direction, gamma);
}

void register_gaussian_traction() {
  register_effect(
      "gaussian_traction",
      [](const core::Params& p, int dim) {
        auto c = p.vector("center", std::size_t(dim));
        auto g = p.vector("direction", std::size_t(dim));
        double n = 0;
        for (double v : g) n += v * v;
        if (!(n > 0)) p.fail("direction", "must be a non-zero vector");
        const double gamma = p.number_in("gamma", 0.0, 1e300, true);
        return make_gaussian_traction(c, g, gamma);
      },
      "Gaussian surface traction g phi(x - p_N) / I_N (scaled by alpha); keys: center (p_N), "
      "direction (g), gamma > 0");
}

}  // namespace hypershape::physics
