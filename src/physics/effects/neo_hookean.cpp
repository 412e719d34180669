/// Effect "neo_hookean": the seed paper's compressible Neo-Hookean material (appendix A).
/// Keys: E (Young's modulus, > 0), nu (Poisson's ratio, in (-1, 0.5)), the modulus field's keys.
#include "hypershape/physics/neo_hookean.hpp"

#include "hypershape/physics/material_params.hpp"

namespace hypershape::physics {

EffectPtr make_neo_hookean(double E, double nu, ScalarFunction field) {
  return make_young_poisson_material<NeoHookean>("neo_hookean", E, nu, std::move(field));
}

void register_neo_hookean() { register_young_poisson_material<NeoHookean>("neo_hookean", "compressible Neo-Hookean material (seed, appendix A)"); }

}  // namespace hypershape::physics
