#include "hypershape/physics/material_params.hpp"

#include <cmath>
#include <memory>

#include "hypershape/core/random.hpp"

namespace hypershape::physics {

YoungPoisson young_poisson(const core::Params& p) {
  const double E = p.number_in("E", 0.0, 1e300, true);
  const double nu = p.number_in("nu", -1.0, 0.5, true, true);
  return {E, nu};
}

LogNormalField::LogNormalField(int dim, double cv, double length, std::uint64_t seed, int n_modes)
    : dim_(dim),
      sigma_(std::sqrt(std::log1p(cv * cv))),
      amplitude_(std::sqrt(2.0 / n_modes)),
      k_(std::size_t(n_modes) * dim),
      phase_(std::size_t(n_modes)) {
  core::RandomStream rng(seed, core::Purpose::material, {std::uint64_t(dim)});
  for (double& k : k_) k = rng.normal() / length;
  for (double& ph : phase_) ph = 2.0 * M_PI * rng.uniform();
}

double LogNormalField::operator()(const double* x) const {
  double g = 0;
  for (std::size_t m = 0; m < phase_.size(); ++m) {
    double arg = phase_[m];
    for (int i = 0; i < dim_; ++i) arg += k_[m * dim_ + i] * x[i];
    g += std::cos(arg);
  }
  return std::exp(sigma_ * amplitude_ * g - 0.5 * sigma_ * sigma_);
}

ScalarFunction modulus_field(const core::Params& p, int dim) {
  const double cv = p.has("E_cv") ? p.number_in("E_cv", 0.0, 10.0) : 0.0;
  const bool length = p.has("E_length"), seed = p.has("E_seed");
  if (cv == 0) {
    if (length || seed) p.fail(length ? "E_length" : "E_seed", "only with E_cv > 0 (a modulus field)");
    return {};
  }
  if (!length) p.fail("E_length", "missing: a modulus field (E_cv > 0) needs its correlation length > 0");
  const double l = p.number_in("E_length", 0.0, 1e300, true);
  const double s = seed ? p.number_in("E_seed", 0.0, 9.0e15) : 0.0;
  if (s != std::floor(s)) p.fail("E_seed", "must be an integer >= 0");
  auto field = std::make_shared<LogNormalField>(dim, cv, l, std::uint64_t(s));
  return [field](const double* x) { return (*field)(x); };
}

std::string modulus_field_help() {
  return "; optional log-normal modulus field m(x) (mean 1) scaling the moduli: E_cv >= 0, E_length > 0, "
         "E_seed (integer; drawn per shape in a dataset)";
}

}  // namespace hypershape::physics
