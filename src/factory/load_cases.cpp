#include "hypershape/factory/load_cases.hpp"

#include <cmath>
#include <numeric>

#include "hypershape/core/random.hpp"

namespace hypershape::factory {

namespace {

/// p_N uniform on the Neumann boundary, g uniform on the unit sphere.
void draw_placement(const geometry::Boundary& b, const std::vector<std::uint8_t>& dirichlet,
                    core::RandomStream& rng, std::array<double, 3>& center, std::array<double, 3>& direction) {
  const int d = b.dim;
  center = geometry::uniform_boundary_point(b, rng, dirichlet);
  double norm = 0;
  do {  // a normal vector normalised is uniform on the sphere
    norm = 0;
    for (int k = 0; k < d; ++k) {
      direction[std::size_t(k)] = rng.normal();
      norm += direction[std::size_t(k)] * direction[std::size_t(k)];
    }
  } while (norm < 1e-20);
  for (int k = 0; k < d; ++k) direction[std::size_t(k)] /= std::sqrt(norm);
}

}  // namespace

std::vector<LoadCase> draw_load_cases(const ShapeSample& shape, const config::LoadsConfig& loads,
                                      std::uint64_t seed, int n_tractions) {
  const auto& b = shape.boundary;
  const auto id = std::uint64_t(shape.shape_id);
  std::vector<std::uint8_t> dirichlet(std::size_t(b.n_facets()), 0);
  for (int f : shape.dirichlet_facets) dirichlet[std::size_t(f)] = 1;

  // Strata: a Fisher-Yates permutation of 0..count-1 per shape.
  const int n = loads.count;
  std::vector<int> stratum(static_cast<std::size_t>(n));
  std::iota(stratum.begin(), stratum.end(), 0);
  core::RandomStream perm(seed, core::Purpose::target, {id});
  for (int i = n - 1; i > 0; --i) {
    const int j = int(perm.uniform() * (i + 1));
    std::swap(stratum[std::size_t(i)], stratum[std::size_t(std::min(j, i))]);
  }

  std::vector<LoadCase> out(static_cast<std::size_t>(n));
  for (int l = 0; l < n; ++l) {
    LoadCase& c = out[std::size_t(l)];
    c.load_id = l;
    core::RandomStream rng(seed, core::Purpose::traction, {id, std::uint64_t(l)});
    draw_placement(b, dirichlet, rng, c.center, c.direction);
    for (int k = 1; k < n_tractions; ++k) {
      core::RandomStream more(seed, core::Purpose::traction, {id, std::uint64_t(l), std::uint64_t(k)});
      draw_placement(b, dirichlet, more, c.more_centers.emplace_back(), c.more_directions.emplace_back());
    }
    core::RandomStream t(seed, core::Purpose::target, {id, std::uint64_t(l)});
    const double u = (stratum[std::size_t(l)] + t.uniform()) / n;
    c.target = loads.target_min + (loads.target_max - loads.target_min) * u;
  }
  return out;
}

}  // namespace hypershape::factory
