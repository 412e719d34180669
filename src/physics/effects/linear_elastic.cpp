/// Effect "linear_elastic": small-strain isotropic linear elasticity (linear_elastic.hpp), the
/// linear problem: one Newton step per load increment. Keys: E > 0, nu in (-1, 0.5), the
/// modulus field's keys.
#include "hypershape/physics/linear_elastic.hpp"

#include "hypershape/physics/hyperelastic.hpp"
#include "hypershape/physics/material_params.hpp"
#include "hypershape/physics/registry.hpp"

namespace hypershape::physics {

EffectPtr make_linear_elastic(double E, double nu, ScalarFunction field) {
  const Lame l = Lame::from_young_poisson(E, nu);
  return std::make_unique<HyperelasticEffect<LinearElastic>>("linear_elastic", LinearElastic<2>{l.mu, l.lambda},
                                                             LinearElastic<3>{l.mu, l.lambda}, std::move(field));
}

void register_linear_elastic() {
  register_effect(
      "linear_elastic",
      [](const core::Params& p, int dim) {
        const YoungPoisson m = young_poisson(p);
        return make_linear_elastic(m.E, m.nu, modulus_field(p, dim));
      },
      "small-strain linear elasticity W = mu eps:eps + lambda/2 (tr eps)^2 (the linear problem); keys: "
      "E > 0, nu in (-1, 0.5)" + modulus_field_help());
}

}  // namespace hypershape::physics
