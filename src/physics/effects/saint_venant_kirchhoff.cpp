/// Effect "saint_venant_kirchhoff": W = lambda/2 (tr E)^2 + mu tr(E^2), E the Green-Lagrange
/// strain (saint_venant_kirchhoff.hpp). Keys: E > 0, nu in (-1, 0.5), the modulus field's keys.
#include "hypershape/physics/saint_venant_kirchhoff.hpp"

#include "hypershape/physics/hyperelastic.hpp"
#include "hypershape/physics/material_params.hpp"
#include "hypershape/physics/registry.hpp"

namespace hypershape::physics {

EffectPtr make_saint_venant_kirchhoff(double E, double nu, ScalarFunction field) {
  const Lame l = Lame::from_young_poisson(E, nu);
  const SaintVenantKirchhoffModel m{l.mu, l.lambda};
  return std::make_unique<HyperelasticEffect<SaintVenantKirchhoff>>(
      "saint_venant_kirchhoff", SaintVenantKirchhoff<2>{{m}}, SaintVenantKirchhoff<3>{{m}}, std::move(field));
}

void register_saint_venant_kirchhoff() {
  register_effect(
      "saint_venant_kirchhoff",
      [](const core::Params& p, int dim) {
        const YoungPoisson m = young_poisson(p);
        return make_saint_venant_kirchhoff(m.E, m.nu, modulus_field(p, dim));
      },
      "Saint Venant-Kirchhoff material W = lambda/2 (tr E)^2 + mu tr E^2 (Green-Lagrange E); keys: "
      "E > 0, nu in (-1, 0.5)" + modulus_field_help());
}

}  // namespace hypershape::physics
