/// Effect "pressure": a dead pressure p on a boundary region, t = -p N with N the outward unit
/// normal of the reference configuration (p > 0 pushes into the body); with `follower: true` the
/// pressure acts on the deformed surface (follower_pressure.cpp). Scaled by alpha (the
/// default) or fixed (scale: fixed). Keys: value (p), the region (region.hpp). Input channel
/// "pressure" (one component): p in the region (at the Neumann nodes; on the grid, at the points
/// of the region), 0 elsewhere.
#include "hypershape/physics/region.hpp"
#include "hypershape/physics/registry.hpp"
#include "hypershape/physics/surface_load.hpp"

namespace hypershape::physics {

EffectPtr make_pressure(double p, const Region& region, int dim) {
  LoadChannel channel{"pressure", 1, [p, region, dim](const double* x, double* v) {
                        v[0] = region.contains(x, dim) ? p : 0.0;
                      }};
  return std::make_unique<SurfaceLoad>(
      "pressure", [p](const double*, const double* n, double* t) { for (int i = 0; i < 3; ++i) t[i] = -p * n[i]; },
      region.facets(), std::move(channel));
}

void register_pressure() {
  register_effect(
      "pressure",
      [](const core::Params& p, int dim) {
        const double value = p.number("value");
        const Region region = Region::from_params(p, dim, false);
        const std::string follower = p.has("follower") ? p.text("follower") : "false";
        if (follower != "true" && follower != "false") p.fail("follower", "must be true or false");
        return follower == "true" ? make_follower_pressure(value, region, dim) : make_pressure(value, region, dim);
      },
      std::string("pressure, dead t = -p N (N: outward normal of the reference configuration) or, with follower: "
                  "true, on the deformed surface t = -p J F^-T N (no energy: LU solves); keys: value (p), ") +
          region_help() + "; follower: false (default) | true; scale: alpha (default) | fixed");
}

}  // namespace hypershape::physics
