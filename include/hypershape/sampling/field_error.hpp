#pragma once
/// The seed paper's error metrics (section 4) for fields given at the nodes of a P1 / P2 mesh:
/// the discrete L2 and H1 norms over the N mesh points
///   ||u||_{L2_N}^2 = 1/N sum_i |u^i|^2,
///   ||u||_{H1_N}^2 = 1/N sum_i (|u^i|^2 + sum_k |d_{x_k} u^i|^2),
/// and the relative errors ||u - u_hat|| / ||u|| (u: the ground truth).
///
/// The paper does not say how the derivatives at the points are obtained. Here, as in
/// scripts/hypershape_data.py (nodal_gradient / rel_h1, the Python readers' implementation, which
/// this one must agree with to round-off: tests/cli/test_study_accuracy.sh compares them), they
/// are the gradient of the P1 (or P2) finite-element interpolant of the nodal values, evaluated at
/// each node in every cell around it and averaged with cell-volume weights. Exact for fields the
/// space contains (linear for P1, quadratic for P2). Nodes in no cell get a zero gradient.
///
/// Plain arrays in and out; serial, not collective, no PETSc.
#include <cstdint>
#include <span>
#include <vector>

namespace hypershape::sampling {

/// Discrete L2 norm sqrt(1/N sum_i |u^i|^2) of `field` (n x n_comp values, node-major).
/// Throws std::invalid_argument if n_comp < 1 or the size is not a multiple of it.
double discrete_l2_norm(std::span<const double> field, int n_comp);

/// The nodal-gradient operator and the H1 norm of one mesh; the per-cell geometry is computed
/// once, so norms of many fields on the same mesh (e.g. the errors of many settings against one
/// reference) cost one pass over the cells each.
class NodalNorms {
 public:
  /// - `dim` 2 or 3; `nodes`: n_nodes x dim coordinates.
  /// - `cells`: n_cells x nodes_per_cell node ids in VTK / XDMF order (P1: dim + 1 vertices;
  ///   P2: the vertices then the edge midpoints, triangle m01 m12 m20, tetrahedron m01 m12 m20
  ///   m03 m13 m23 -- physics::Space::canonical_cells). Straight-sided: the geometry is the
  ///   vertices'.
  /// Throws std::invalid_argument for a bad dim, a nodes-per-cell count that is neither P1 nor
  /// P2, sizes that do not match, an id out of range or a cell of zero volume.
  NodalNorms(int dim, std::span<const double> nodes, std::span<const std::int64_t> cells,
             int nodes_per_cell);

  int dim() const { return dim_; }
  std::size_t n_nodes() const { return n_nodes_; }

  /// Recovered nodal gradient: n_nodes x n_comp x dim values, out[(i * n_comp + c) * dim + k] =
  /// d u_c / d x_k at node i. `field`: n_nodes x n_comp values.
  std::vector<double> gradient(std::span<const double> field, int n_comp) const;
  /// ||field||_{H1_N} (with the recovered gradient).
  double h1_norm(std::span<const double> field, int n_comp) const;
  /// ||u - u_hat||_{L2_N} / ||u||_{L2_N} and the same in H1_N; u is the ground truth. Both
  /// n_nodes x n_comp. The gradient is linear in the field, so the difference is differentiated.
  double rel_l2(std::span<const double> u, std::span<const double> u_hat, int n_comp) const;
  double rel_h1(std::span<const double> u, std::span<const double> u_hat, int n_comp) const;

 private:
  void check(std::span<const double> field, int n_comp) const;
  /// u - u_hat, after checking both sizes.
  std::vector<double> difference(std::span<const double> u, std::span<const double> u_hat, int n_comp) const;
  int dim_ = 0, width_ = 0;
  std::size_t n_nodes_ = 0, n_cells_ = 0;
  std::vector<std::int64_t> cells_;
  std::vector<double> grad_lambda_;  ///< n_cells x (dim + 1) x dim: gradients of barycentrics
  std::vector<double> weight_;       ///< n_cells: |volume| (the constant factor cancels)
  std::vector<double> weight_sum_;   ///< n_nodes: sum of the weights of the cells around
};

}  // namespace hypershape::sampling
