/// Effect "uniform_traction": a uniform dead traction t (per unit reference area) on a
/// boundary region. Keys: value (t, a vector), the region (region.hpp); scale: alpha | fixed.
/// Input channel "traction": t in the region (at the Neumann nodes; on the grid, at the points
/// of the region), 0 elsewhere.
#include "hypershape/physics/region.hpp"
#include "hypershape/physics/registry.hpp"
#include "hypershape/physics/surface_load.hpp"

namespace hypershape::physics {

EffectPtr make_uniform_traction(const std::vector<double>& t, const Region& region) {
  const int dim = int(t.size());
  LoadChannel channel{"traction", 0, [t, region, dim](const double* x, double* v) {
                        const bool in = region.contains(x, dim);
                        for (int i = 0; i < dim; ++i) v[i] = in ? t[std::size_t(i)] : 0.0;
                      }};
  return std::make_unique<SurfaceLoad>(
      "uniform_traction",
      [t, dim](const double*, const double*, double* v) { for (int i = 0; i < dim; ++i) v[i] = t[std::size_t(i)]; },
      region.facets(), std::move(channel));
}

void register_uniform_traction() {
  register_effect(
      "uniform_traction",
      [](const core::Params& p, int dim) {
        return make_uniform_traction(p.vector("value", std::size_t(dim)), Region::from_params(p, dim, false));
      },
      std::string("uniform dead traction per unit reference area; keys: value (a vector), ") + region_help() +
          "; scale: alpha (default) | fixed");
}

}  // namespace hypershape::physics
