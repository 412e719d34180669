/// Effect "linear_elastic": small-strain isotropic linear elasticity (linear_elastic.hpp), the
/// linear problem: one Newton step per load increment. Keys: E > 0, nu in (-1, 0.5), the
/// modulus field's keys.
#include "hypershape/physics/linear_elastic.hpp"

#include "hypershape/physics/material_params.hpp"

namespace hypershape::physics {

EffectPtr make_linear_elastic(double E, double nu, ScalarFunction field) {
  return make_young_poisson_material<LinearElastic>("linear_elastic", E, nu, std::move(field));
}

void register_linear_elastic() { register_young_poisson_material<LinearElastic>("linear_elastic", "small-strain linear elasticity W = mu eps:eps + lambda/2 (tr eps)^2 (the linear problem)"); }

}  // namespace hypershape::physics
