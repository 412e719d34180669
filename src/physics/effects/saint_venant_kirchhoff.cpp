/// Effect "saint_venant_kirchhoff": W = lambda/2 (tr E)^2 + mu tr(E^2), E the Green-Lagrange
/// strain (saint_venant_kirchhoff.hpp). Keys: E > 0, nu in (-1, 0.5), the modulus field's keys.
#include "hypershape/physics/saint_venant_kirchhoff.hpp"

#include "hypershape/physics/material_params.hpp"

namespace hypershape::physics {

EffectPtr make_saint_venant_kirchhoff(double E, double nu, ScalarFunction field) {
  return make_young_poisson_material<SaintVenantKirchhoff>("saint_venant_kirchhoff", E, nu, std::move(field));
}

void register_saint_venant_kirchhoff() { register_young_poisson_material<SaintVenantKirchhoff>("saint_venant_kirchhoff", "Saint Venant-Kirchhoff material W = lambda/2 (tr E)^2 + mu tr E^2 (Green-Lagrange E)"); }

}  // namespace hypershape::physics
