#pragma once
/// What the material effects share: reading (E, nu) with their ranges, and the optional
/// log-normal modulus field that scales any material's energy, W(x, F) = m(x) W(F):
///   m(x) = exp(s g(x) - s^2 / 2),  s^2 = ln(1 + cv^2),
/// so that E(x) = E m(x) has mean E and coefficient of variation cv. g is a stationary
/// Gaussian random field of unit variance and covariance exp(-|x - y|^2 / (2 l^2)), drawn as
/// random Fourier features (Rahimi and Recht 2007): g(x) = sqrt(2/M) sum_m cos(k_m . x + phi_m),
/// k_m ~ N(0, I / l^2), phi_m ~ U[0, 2 pi), M = 256 modes. It is a pure function of
/// (seed, x): the same on any rank count and mesh. Keys: E_cv (>= 0; 0 or absent: homogeneous),
/// E_length (l > 0, with E_cv), E_seed (an integer >= 0; a dataset draws it per shape).
#include <cstdint>
#include <string>
#include <vector>

#include "hypershape/core/params.hpp"
#include "hypershape/physics/hyperelastic.hpp"
#include "hypershape/physics/registry.hpp"

namespace hypershape::physics {

struct YoungPoisson {
  double E, nu;
};

/// Reads E > 0 and nu in (-1, 0.5); errors name the key and the range.
YoungPoisson young_poisson(const core::Params& p);

/// The log-normal modulus factor m(x) described above. Cheap to copy (shares its modes).
class LogNormalField {
 public:
  LogNormalField(int dim, double cv, double length, std::uint64_t seed, int n_modes = 256);
  double operator()(const double* x) const;

 private:
  int dim_;
  double sigma_, amplitude_;
  std::vector<double> k_, phase_;  ///< n_modes x dim wave vectors, n_modes phases
};

/// Inclusions: `count` balls (discs in 2D) of radius r whose centres are uniform in the box
/// [-1, 1]^dim (the normalised shapes' box; balls may overlap or stick out of the body), drawn
/// from the stream (seed, material, {dim, inclusions}): m(x) = ratio inside any ball, 1 outside.
/// A pure function of (seed, x), like LogNormalField.
class InclusionField {
 public:
  InclusionField(int dim, int count, double radius, double ratio, std::uint64_t seed);
  double operator()(const double* x) const;
  /// count x dim centres, row-major.
  const std::vector<double>& centers() const { return centers_; }

 private:
  int dim_;
  double radius2_, ratio_;
  std::vector<double> centers_;
};

/// The modulus field of an effect's keys E_cv, E_length (log-normal), inclusions,
/// inclusion_radius, inclusion_ratio (inclusions) and E_seed (both): their product; empty when
/// neither is asked for.
ScalarFunction modulus_field(const core::Params& p, int dim);
/// The keys above for a help line.
std::string modulus_field_help();

/// A material of kernel family K whose constants are (mu, lambda), from E and nu.
template <template <int> class K>
EffectPtr make_young_poisson_material(std::string name, double E, double nu, ScalarFunction field) {
  const Lame l = Lame::from_young_poisson(E, nu);
  const double c[2] = {l.mu, l.lambda};
  return std::make_unique<HyperelasticEffect<K>>(std::move(name), K<2>::from_constants(c), K<3>::from_constants(c),
                                                 std::move(field));
}

/// Registers such a material under `name` with keys E, nu and the modulus field's.
template <template <int> class K>
void register_young_poisson_material(const std::string& name, const std::string& help) {
  register_effect(
      name,
      [name](const core::Params& p, int dim) {
        const YoungPoisson m = young_poisson(p);
        return make_young_poisson_material<K>(name, m.E, m.nu, modulus_field(p, dim));
      },
      help + "; keys: E > 0, nu in (-1, 0.5)" + modulus_field_help());
}

}  // namespace hypershape::physics
