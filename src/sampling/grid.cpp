#include "hypershape/sampling/grid.hpp"

#include <cstddef>
#include <stdexcept>
#include <string>

namespace hypershape::sampling {

std::vector<double> grid_points(int dim, int n) {
  if (dim != 2 && dim != 3)
    throw std::invalid_argument("grid_points: dimension must be 2 or 3, got " +
                                std::to_string(dim));
  if (n < 2)
    throw std::invalid_argument("grid_points: need at least 2 nodes per axis, got " +
                                std::to_string(n));
  // Computed as (2 i - (n - 1)) / (n - 1): exact at both ends and symmetric about 0.
  std::vector<double> axis(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) axis[std::size_t(i)] = double(2 * i - (n - 1)) / double(n - 1);
  const std::size_t m = std::size_t(n);
  std::vector<double> x;
  x.reserve(dim == 2 ? m * m * 2 : m * m * m * 3);
  if (dim == 2) {
    for (std::size_t i = 0; i < m; ++i)
      for (std::size_t j = 0; j < m; ++j) x.insert(x.end(), {axis[i], axis[j]});
  } else {
    for (std::size_t i = 0; i < m; ++i)
      for (std::size_t j = 0; j < m; ++j)
        for (std::size_t k = 0; k < m; ++k) x.insert(x.end(), {axis[i], axis[j], axis[k]});
  }
  return x;
}

}  // namespace hypershape::sampling
