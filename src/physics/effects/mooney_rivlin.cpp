/// Effect "mooney_rivlin": compressible Mooney-Rivlin, W = C1 (Ib1 - 3) + C2 (Ib2 - 3) +
/// kappa/2 (J - 1)^2 (mooney_rivlin.hpp; Holzapfel 2000, Abaqus D1 = 2 / kappa).
/// Keys: C1 >= 0, C2 >= 0 (C1 + C2 > 0), exactly one of kappa > 0 or D1 > 0, the modulus
/// field's keys (the field scales C1, C2 and kappa together).
#include "hypershape/physics/mooney_rivlin.hpp"

#include "hypershape/physics/hyperelastic.hpp"
#include "hypershape/physics/material_params.hpp"
#include "hypershape/physics/registry.hpp"

namespace hypershape::physics {

EffectPtr make_mooney_rivlin(double C1, double C2, double kappa, ScalarFunction field) {
  const MooneyRivlinModel m{C1, C2, kappa};
  return std::make_unique<HyperelasticEffect<MooneyRivlin>>("mooney_rivlin", MooneyRivlin<2>{{m}},
                                                            MooneyRivlin<3>{{m}}, std::move(field));
}

void register_mooney_rivlin() {
  register_effect(
      "mooney_rivlin",
      [](const core::Params& p, int dim) {
        const double C1 = p.number_in("C1", 0.0, 1e300), C2 = p.number_in("C2", 0.0, 1e300);
        if (!(C1 + C2 > 0)) p.fail("C1", "C1 + C2 must be > 0 (the shear modulus is 2 (C1 + C2))");
        if (p.has("kappa") == p.has("D1")) p.fail("kappa", "give exactly one of kappa (bulk modulus) or D1 = 2 / kappa");
        const double kappa = p.has("kappa") ? p.number_in("kappa", 0.0, 1e300, true)
                                            : 2.0 / p.number_in("D1", 0.0, 1e300, true);
        return make_mooney_rivlin(C1, C2, kappa, modulus_field(p, dim));
      },
      "compressible Mooney-Rivlin W = C1 (Ib1 - 3) + C2 (Ib2 - 3) + kappa/2 (J - 1)^2 (isochoric "
      "invariants; mu = 2 (C1 + C2)); keys: C1 >= 0, C2 >= 0, kappa > 0 or D1 = 2/kappa > 0" +
          modulus_field_help());
}

}  // namespace hypershape::physics
