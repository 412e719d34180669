/// Effect "neo_hookean": the seed paper's compressible Neo-Hookean material (appendix A).
/// Keys: E (Young's modulus, > 0), nu (Poisson's ratio, in (-1, 0.5)), dilatation (pointwise,
/// the default, or mean: the volumetric energy on each cell's mean dilatation, mean_dilatation.cpp),
/// pointwise_share (with mean: the share of it kept pointwise),
/// the modulus field's keys.
#include "hypershape/physics/neo_hookean.hpp"

#include "hypershape/physics/material_params.hpp"

namespace hypershape::physics {

EffectPtr make_neo_hookean(double E, double nu, ScalarFunction field) {
  return make_young_poisson_material<NeoHookean>("neo_hookean", E, nu, std::move(field));
}

void register_neo_hookean() {
  register_effect(
      "neo_hookean",
      [](const core::Params& p, int dim) {
        const YoungPoisson m = young_poisson(p);
        const std::string dilatation = p.has("dilatation") ? p.text("dilatation") : "pointwise";
        if (dilatation != "pointwise" && dilatation != "mean")
          p.fail("dilatation", "'" + dilatation + "' is not one of: pointwise, mean");
        if (dilatation != "mean" && p.has("pointwise_share"))
          p.fail("pointwise_share", "applies to dilatation: mean only");
        const double share = dilatation == "mean" ? p.number_or("pointwise_share", 0.0) : 0.0;
        if (!(share >= 0 && share < 1)) p.fail("pointwise_share", "must be in [0, 1)");
        return dilatation == "mean" ? make_neo_hookean_mean_dilatation(m.E, m.nu, modulus_field(p, dim), share)
                                    : make_neo_hookean(m.E, m.nu, modulus_field(p, dim));
      },
      "compressible Neo-Hookean material (seed, appendix A); keys: E > 0, nu in (-1, 0.5), dilatation: "
      "pointwise (default) or mean (lambda/2 ln^2 of each cell's mean dilatation: locking-free on P2 "
      "meshes near incompressibility; on P1 the same as pointwise), pointwise_share in [0, 1) (with mean: "
      "that share of lambda on the pointwise dilatation, default 0)" +
          modulus_field_help());
}

}  // namespace hypershape::physics
