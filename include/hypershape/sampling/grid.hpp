#pragma once
/// The regular grids over [-1, 1]^d on which the grid representations (paper, section 3.3) are
/// stored: SDF, distance to the Dirichlet patch, traction and displacement.
#include <vector>

namespace hypershape::sampling {

/// The n^dim nodes of the regular grid over [-1, 1]^dim, x = -1 + 2 i / (n - 1) along each axis
/// (so -1 and 1 are nodes, exactly), as n^dim * dim coordinates.
///
/// Order: numpy's 'ij' indexing in C order, the x index slowest: node (i0, i1[, i2]) has flat
/// index (i0 * n + i1) * n + i2, so that a per-node array reshaped to (n, n[, n]) in numpy is
/// indexed a[i, j, k] = f(x_i, y_j, z_k).
///
/// Throws std::invalid_argument if dim is not 2 or 3 or n < 2. Not collective.
std::vector<double> grid_points(int dim, int n);

}  // namespace hypershape::sampling
