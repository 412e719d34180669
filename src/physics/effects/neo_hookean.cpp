/// Effect "neo_hookean": the seed paper's compressible Neo-Hookean material (appendix A).
/// Keys: E (Young's modulus, > 0), nu (Poisson's ratio, in (-1, 0.5)).
#include "hypershape/physics/neo_hookean.hpp"

#include "hypershape/physics/hyperelastic.hpp"
#include "hypershape/physics/material_params.hpp"
#include "hypershape/physics/registry.hpp"

namespace hypershape::physics {

EffectPtr make_neo_hookean(double E, double nu, ScalarFunction field) {
  const Lame l = Lame::from_young_poisson(E, nu);
  return std::make_unique<HyperelasticEffect<NeoHookean>>("neo_hookean", NeoHookean<2>{l.mu, l.lambda},
                                                          NeoHookean<3>{l.mu, l.lambda}, std::move(field));
}

void register_neo_hookean() {
  register_effect(
      "neo_hookean",
      [](const core::Params& p, int dim) {
        const YoungPoisson m = young_poisson(p);
        return make_neo_hookean(m.E, m.nu, modulus_field(p, dim));
      },
      "compressible Neo-Hookean material (seed, appendix A); keys: E > 0, nu in (-1, 0.5)" +
          modulus_field_help());
}

}  // namespace hypershape::physics
