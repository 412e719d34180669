#include "hypershape/sampling/field_error.hpp"
#include "hypershape/mesh/reference_cell.hpp"

#include <Eigen/Dense>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

namespace hypershape::sampling {

namespace {

/// C[(n * k + j) * nv + a] = d phi_j / d lambda_a at local node n of the k-node simplex: the
/// gradient of basis j at node n is sum_a C[n, j, a] grad(lambda_a).
std::vector<double> basis_gradients_at_nodes(int dim, int k) {
  const int nv = dim + 1;
  std::vector<double> C(std::size_t(k * k * nv), 0.0);
  auto at = [&](int n, int j, int a) -> double& { return C[std::size_t((n * k + j) * nv + a)]; };
  if (k == nv) {  // P1: phi_j = lambda_j
    for (int n = 0; n < k; ++n)
      for (int j = 0; j < k; ++j) at(n, j, j) = 1.0;
    return C;
  }
  const auto edges = mesh::edges(dim);
  const int n_edges = int(edges.size());
  std::vector<std::array<double, 4>> bary(std::size_t(k), {0, 0, 0, 0});
  for (int v = 0; v < nv; ++v) bary[std::size_t(v)][std::size_t(v)] = 1.0;
  for (int e = 0; e < n_edges; ++e)
    bary[std::size_t(nv + e)][std::size_t(edges[e].first)] = bary[std::size_t(nv + e)][std::size_t(edges[e].second)] = 0.5;
  for (int n = 0; n < k; ++n) {
    const auto& lam = bary[std::size_t(n)];
    for (int j = 0; j < nv; ++j) at(n, j, j) = 4.0 * lam[std::size_t(j)] - 1.0;  // lambda_j (2 lambda_j - 1)
    for (int e = 0; e < n_edges; ++e) {  // 4 lambda_a lambda_b
      const auto [a, b] = edges[std::size_t(e)];
      at(n, nv + e, a) = 4.0 * lam[std::size_t(b)];
      at(n, nv + e, b) = 4.0 * lam[std::size_t(a)];
    }
  }
  return C;
}

}  // namespace

double discrete_l2_norm(std::span<const double> field, int n_comp) {
  if (n_comp < 1 || field.size() % std::size_t(n_comp) != 0)
    throw std::invalid_argument("discrete_l2_norm: field size is not a multiple of n_comp >= 1");
  const std::size_t n = field.size() / std::size_t(n_comp);
  if (n == 0) return 0.0;
  double s = 0.0;
  for (double v : field) s += v * v;
  return std::sqrt(s / double(n));
}

NodalNorms::NodalNorms(int dim, std::span<const double> nodes, std::span<const std::int64_t> cells,
                       int nodes_per_cell)
    : dim_(dim), width_(nodes_per_cell) {
  if (dim != 2 && dim != 3) throw std::invalid_argument("NodalNorms: dim must be 2 or 3");
  const int nv = dim + 1, n_p2 = dim == 2 ? 6 : 10;
  if (nodes_per_cell != nv && nodes_per_cell != n_p2)
    throw std::invalid_argument("NodalNorms: " + std::to_string(nodes_per_cell) +
                                " nodes per cell is neither P1 nor P2 in " + std::to_string(dim) + "D");
  if (nodes.size() % std::size_t(dim) != 0 || cells.size() % std::size_t(nodes_per_cell) != 0)
    throw std::invalid_argument("NodalNorms: array sizes do not match dim / nodes_per_cell");
  n_nodes_ = nodes.size() / std::size_t(dim);
  n_cells_ = cells.size() / std::size_t(nodes_per_cell);
  cells_.assign(cells.begin(), cells.end());
  for (std::int64_t id : cells_)
    if (id < 0 || std::size_t(id) >= n_nodes_) throw std::invalid_argument("NodalNorms: node id out of range");
  grad_lambda_.assign(n_cells_ * std::size_t(nv * dim), 0.0);
  weight_.assign(n_cells_, 0.0);
  weight_sum_.assign(n_nodes_, 0.0);
  for (std::size_t c = 0; c < n_cells_; ++c) {
    const std::int64_t* v = &cells_[c * std::size_t(width_)];
    Eigen::Matrix3d J = Eigen::Matrix3d::Identity();  // rows x_a - x_0, a = 1..dim
    for (int a = 0; a < dim; ++a)
      for (int k = 0; k < dim; ++k)
        J(a, k) = nodes[std::size_t(v[a + 1]) * std::size_t(dim) + std::size_t(k)] -
                  nodes[std::size_t(v[0]) * std::size_t(dim) + std::size_t(k)];
    const double det = J.topLeftCorner(dim, dim).determinant();
    if (det == 0.0 || !std::isfinite(det)) throw std::invalid_argument("NodalNorms: degenerate cell (zero volume)");
    // lambda = J^-T (x - x_0) for a = 1..dim, so grad lambda_a is column a of J^-1.
    Eigen::MatrixXd Jinv = J.topLeftCorner(dim, dim).inverse();
    double* g = &grad_lambda_[c * std::size_t(nv * dim)];
    for (int k = 0; k < dim; ++k) {
      double sum = 0.0;
      for (int a = 1; a < nv; ++a) {
        g[a * dim + k] = Jinv(k, a - 1);
        sum += Jinv(k, a - 1);
      }
      g[k] = -sum;
    }
    weight_[c] = std::abs(det);
    for (int n = 0; n < width_; ++n) weight_sum_[std::size_t(v[n])] += weight_[c];
  }
}

void NodalNorms::check(std::span<const double> field, int n_comp) const {
  if (n_comp < 1 || field.size() != n_nodes_ * std::size_t(n_comp))
    throw std::invalid_argument("NodalNorms: field has " + std::to_string(field.size()) + " values, expected " +
                                std::to_string(n_nodes_) + " x n_comp");
}

std::vector<double> NodalNorms::gradient(std::span<const double> field, int n_comp) const {
  check(field, n_comp);
  const int d = dim_, nv = d + 1, k = width_;
  const auto C = basis_gradients_at_nodes(d, k);
  const std::size_t per = std::size_t(n_comp * d);
  std::vector<double> out(n_nodes_ * per, 0.0);
  std::vector<double> dphi(std::size_t(k * d));  // d phi_j / d x at one node
  for (std::size_t c = 0; c < n_cells_; ++c) {
    const std::int64_t* v = &cells_[c * std::size_t(k)];
    const double* gl = &grad_lambda_[c * std::size_t(nv * d)];
    for (int n = 0; n < k; ++n) {
      for (int j = 0; j < k; ++j)
        for (int x = 0; x < d; ++x) {
          double s = 0.0;
          for (int a = 0; a < nv; ++a) s += C[std::size_t((n * k + j) * nv + a)] * gl[a * d + x];
          dphi[std::size_t(j * d + x)] = s;
        }
      double* o = &out[std::size_t(v[n]) * per];
      for (int j = 0; j < k; ++j) {
        const double* u = &field[std::size_t(v[j]) * std::size_t(n_comp)];
        for (int cc = 0; cc < n_comp; ++cc)
          for (int x = 0; x < d; ++x) o[cc * d + x] += weight_[c] * u[cc] * dphi[std::size_t(j * d + x)];
      }
    }
  }
  for (std::size_t i = 0; i < n_nodes_; ++i)
    if (weight_sum_[i] > 0)
      for (std::size_t q = 0; q < per; ++q) out[i * per + q] /= weight_sum_[i];
  return out;
}

double NodalNorms::h1_norm(std::span<const double> field, int n_comp) const {
  check(field, n_comp);
  if (n_nodes_ == 0) return 0.0;
  const auto g = gradient(field, n_comp);
  double s = 0.0;
  for (double v : field) s += v * v;
  for (double v : g) s += v * v;
  return std::sqrt(s / double(n_nodes_));
}

std::vector<double> NodalNorms::difference(std::span<const double> u, std::span<const double> u_hat,
                                           int n_comp) const {
  check(u, n_comp);
  check(u_hat, n_comp);
  std::vector<double> diff(u.size());
  for (std::size_t i = 0; i < u.size(); ++i) diff[i] = u[i] - u_hat[i];
  return diff;
}

double NodalNorms::rel_l2(std::span<const double> u, std::span<const double> u_hat, int n_comp) const {
  return discrete_l2_norm(difference(u, u_hat, n_comp), n_comp) / discrete_l2_norm(u, n_comp);
}

double NodalNorms::rel_h1(std::span<const double> u, std::span<const double> u_hat, int n_comp) const {
  return h1_norm(difference(u, u_hat, n_comp), n_comp) / h1_norm(u, n_comp);
}

}  // namespace hypershape::sampling
