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

InclusionField::InclusionField(int dim, int count, double radius, double ratio, std::uint64_t seed)
    : dim_(dim), radius2_(radius * radius), ratio_(ratio), centers_(std::size_t(count * dim)) {
  // Its own stream (key 1), so that adding inclusions leaves a log-normal field unchanged.
  core::RandomStream rng(seed, core::Purpose::material, {std::uint64_t(dim), 1});
  for (double& c : centers_) c = 2.0 * rng.uniform() - 1.0;
}

double InclusionField::operator()(const double* x) const {
  for (std::size_t c = 0; c < centers_.size(); c += std::size_t(dim_)) {
    double r2 = 0;
    for (int i = 0; i < dim_; ++i) r2 += (x[i] - centers_[c + std::size_t(i)]) * (x[i] - centers_[c + std::size_t(i)]);
    if (r2 <= radius2_) return ratio_;
  }
  return 1.0;
}

namespace {

/// The seed key E_seed (an integer >= 0, default 0).
std::uint64_t field_seed(const core::Params& p) {
  const double s = p.has("E_seed") ? p.number_in("E_seed", 0.0, 9.0e15) : 0.0;
  if (s != std::floor(s)) p.fail("E_seed", "must be an integer >= 0");
  return std::uint64_t(s);
}

/// The log-normal field of E_cv, E_length, or null.
std::shared_ptr<LogNormalField> log_normal(const core::Params& p, int dim) {
  const double cv = p.has("E_cv") ? p.number_in("E_cv", 0.0, 10.0) : 0.0;
  if (cv == 0) {
    if (p.has("E_length")) p.fail("E_length", "only with E_cv > 0 (a modulus field)");
    return nullptr;
  }
  if (!p.has("E_length")) p.fail("E_length", "missing: a modulus field (E_cv > 0) needs its correlation length > 0");
  const double l = p.number_in("E_length", 0.0, 1e300, true);
  return std::make_shared<LogNormalField>(dim, cv, l, field_seed(p));
}

/// The inclusions of inclusions, inclusion_radius, inclusion_ratio, or null.
std::shared_ptr<InclusionField> inclusions(const core::Params& p, int dim) {
  const double n = p.has("inclusions") ? p.number_in("inclusions", 0.0, 1000.0) : 0.0;
  if (n != std::floor(n)) p.fail("inclusions", "a count: an integer in [0, 1000]");
  if (n == 0) {
    for (const char* key : {"inclusion_radius", "inclusion_ratio"})
      if (p.has(key)) p.fail(key, "only with inclusions >= 1 (their count)");
    return nullptr;
  }
  for (const char* key : {"inclusion_radius", "inclusion_ratio"})
    if (!p.has(key)) p.fail(key, "missing: inclusions need inclusion_radius > 0 and inclusion_ratio > 0");
  const double r = p.number_in("inclusion_radius", 0.0, 2.0, true);
  const double ratio = p.number_in("inclusion_ratio", 0.0, 1e6, true);
  return std::make_shared<InclusionField>(dim, int(n), r, ratio, field_seed(p));
}

}  // namespace

ScalarFunction modulus_field(const core::Params& p, int dim) {
  auto ln = log_normal(p, dim);
  auto inc = inclusions(p, dim);
  if (!ln && !inc) {
    if (p.has("E_seed")) p.fail("E_seed", "only with E_cv > 0 or inclusions (a modulus field)");
    return {};
  }
  if (!inc) return [ln](const double* x) { return (*ln)(x); };
  if (!ln) return [inc](const double* x) { return (*inc)(x); };
  return [ln, inc](const double* x) { return (*ln)(x) * (*inc)(x); };
}

std::string modulus_field_help() {
  return "; optional modulus field m(x) scaling the moduli: log-normal (mean 1) E_cv >= 0, E_length > 0; "
         "inclusions (count), inclusion_radius > 0, inclusion_ratio > 0 (m inside); E_seed (integer; drawn per "
         "shape in a dataset)";
}

}  // namespace hypershape::physics
