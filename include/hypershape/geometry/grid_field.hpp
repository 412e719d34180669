#pragma once
/// Vector fields on regular grids: Gaussian-random-field velocity samples and the displacement
/// fields of their flows. Catmull-Rom (cubic) interpolation between nodes.
#include <array>
#include <cstdint>
#include <span>
#include <cstddef>
#include <vector>

#include "hypershape/core/random.hpp"

namespace hypershape::geometry {

/// A regular grid: n[a] nodes along axis a at lower[a] + i * spacing. Unused axes have n = 1.
struct Grid {
  int dim = 2;
  std::array<double, 3> lower{};
  double spacing = 1.0;
  std::array<int, 3> n{1, 1, 1};

  std::int64_t n_nodes() const { return std::int64_t(n[0]) * n[1] * n[2]; }
  /// The grid covering [lo, hi] (per axis) with nodes `spacing` apart.
  static Grid covering(int dim, std::span<const double> lo, std::span<const double> hi,
                       double spacing);
};

/// A field of `dim` components at the nodes of a grid (node (i, j, k) has index
/// i + n0 * (j + n1 * k)), stored node by node (the components of a node side by side, as
/// evaluation reads them). Evaluation between nodes is tensor-product Catmull-Rom: C1 and exact
/// for quadratics, so the interpolation error is O(spacing^3); outside the grid the field is
/// continued by its value at the nearest node.
class GridField {
 public:
  explicit GridField(const Grid& grid);
  const Grid& grid() const { return grid_; }
  int dim() const { return grid_.dim; }
  /// Component c at node `node`.
  double& at(std::int64_t node, int c) { return values_[std::size_t(node * grid_.dim + c)]; }
  double at(std::int64_t node, int c) const { return values_[std::size_t(node * grid_.dim + c)]; }
  /// Coordinates of node `node` (dim entries written to x).
  void node_coords(std::int64_t node, double* x) const;
  /// Interpolated value at x (dim coordinates in, dim components out).
  void evaluate(const double* x, double* value) const;
  /// The same at n points (x: n x dim coordinates, values: n x dim components), each to the bit
  /// what evaluate(x, value) gives it alone, and faster: four points at a time, each point's sum
  /// in the same order, their additions overlapping in the CPU.
  void evaluate(std::size_t n, const double* x, double* values) const;
  /// Largest Euclidean norm over the nodes.
  double max_norm() const;

 private:
  Grid grid_;
  std::vector<double> values_;  ///< node-major; one spare entry at the end (a 3D node's values
                                ///< are read as four lanes, the fourth unused)
};

/// Samples a velocity field whose components are independent zero-mean Gaussian random fields
/// with covariance m^2 exp(-|x - y|^2 / (2 sigma^2)) at the nodes of `grid`. The sample is exact
/// at the nodes (to round-off): the Gaussian kernel is separable, so the covariance matrix of the
/// node values is the Kronecker product C_x (x) C_y (x) C_z of 1D kernel matrices, and
/// v = m (A_x (x) A_y (x) A_z) xi with A A^T = C (symmetric eigen square root) and xi iid
/// standard normal from `rng` (node-major within each component).
GridField sample_velocity_field(const Grid& grid, double sigma, double m, core::RandomStream& rng);

/// The displacement u of the time-1 flow of the stationary velocity v: phi(x, 1) = x + u(x),
/// d phi / dt = v(phi), by scaling and squaring (Arsigny et al. 2006): a second-order (midpoint)
/// step u_0(x) = tau v(x + tau v(x) / 2) with tau = 2^-n_squarings, then n_squarings
/// compositions u <- u + u(x + u). Same grid as v; v is taken by value so that a caller that
/// moves it in lends its storage (peak memory: two fields).
GridField exponentiate(GridField v, int n_squarings);

/// Squarings that make the first step small against the grid: max|v| 2^-n <= spacing / 8.
int default_squarings(const GridField& v);

}  // namespace hypershape::geometry
