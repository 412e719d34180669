/// Effect "dirichlet": u_i = 0 on the boundary facets of a region (a clamped edge or face:
/// box of zero width; a roller: one component). Keys: the region (required, region.hpp),
/// components (a list of component indices; default all).
#include <atomic>
#include <cmath>

#include "hypershape/physics/region.hpp"
#include "hypershape/physics/registry.hpp"

namespace hypershape::physics {

namespace {

std::vector<PetscInt> components(const core::Params& p, int dim) {
  std::vector<PetscInt> out;
  if (!p.has("components")) return out;
  for (double c : p.vector("components", 0)) {
    if (!(c >= 0 && c < dim && c == std::floor(c)))
      p.fail("components", "component indices must be integers in [0, " + std::to_string(dim - 1) + "]");
    out.push_back(PetscInt(c));
  }
  return out;
}

}  // namespace

void register_dirichlet_region() {
  register_effect(
      "dirichlet",
      [](const core::Params& p, int dim) {
        const Region r = Region::from_params(p, dim, true);
        static std::atomic<int> n_made{0};  // each instance its own label
        return make_dirichlet("dirichlet_" + std::to_string(n_made++), r.facets(), components(p, dim));
      },
      "u_i = 0 on the boundary facets in a region (a clamped edge; a roller with one component); keys: "
      "box [lower corner, upper corner] or center + radius (required), components (list of indices, "
      "default all)");
}

}  // namespace hypershape::physics
