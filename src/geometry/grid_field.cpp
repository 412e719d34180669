#include "hypershape/geometry/grid_field.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstring>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <tuple>
#include <type_traits>
#include <vector>

namespace hypershape::geometry {

Grid Grid::covering(int dim, std::span<const double> lo, std::span<const double> hi,
                    double spacing) {
  assert(dim == 2 || dim == 3);
  Grid g;
  g.dim = dim;
  g.spacing = spacing;
  for (int a = 0; a < dim; ++a) {
    const int cells = std::max(1, int(std::ceil((hi[a] - lo[a]) / spacing)));
    // Centre the node lattice on the box so that the cover is symmetric.
    const double extra = cells * spacing - (hi[a] - lo[a]);
    g.lower[a] = lo[a] - 0.5 * extra;
    g.n[a] = cells + 1;
  }
  return g;
}

GridField::GridField(const Grid& grid)
    : grid_(grid), values_(std::size_t(grid.dim * grid.n_nodes()) + 1, 0.0) {}

void GridField::node_coords(std::int64_t node, double* x) const {
  const std::int64_t i = node % grid_.n[0];
  const std::int64_t j = (node / grid_.n[0]) % grid_.n[1];
  const std::int64_t k = node / (std::int64_t(grid_.n[0]) * grid_.n[1]);
  const std::int64_t ijk[3] = {i, j, k};
  for (int a = 0; a < grid_.dim; ++a) x[a] = grid_.lower[a] + double(ijk[a]) * grid_.spacing;
}

namespace {

/// Catmull-Rom weights of nodes i-1..i+2 for the local coordinate t in [0, 1).
inline void catmull_rom(double t, double w[4]) {
  const double t2 = t * t, t3 = t2 * t;
  w[0] = 0.5 * (-t3 + 2.0 * t2 - t);
  w[1] = 0.5 * (3.0 * t3 - 5.0 * t2 + 2.0);
  w[2] = 0.5 * (-3.0 * t3 + 4.0 * t2 + t);
  w[3] = 0.5 * (t3 - t2);
}

/// Stencil along one axis: clamped node indices and weights.
inline void stencil(double x, double lower, double spacing, int n, int idx[4], double w[4]) {
  if (n == 1) {
    idx[0] = idx[1] = idx[2] = idx[3] = 0;
    w[0] = w[2] = w[3] = 0.0;
    w[1] = 1.0;
    return;
  }
  double s = (x - lower) / spacing;
  s = std::clamp(s, 0.0, double(n - 1));
  int i = std::min(int(s), n - 2);
  catmull_rom(s - i, w);
  for (int q = 0; q < 4; ++q) idx[q] = std::clamp(i - 1 + q, 0, n - 1);
}

/// Two and four doubles in vector registers (four: one AVX register where the CPU has it, two
/// SSE ones where not); every operation on them is one IEEE operation per lane, and no fused
/// multiply-add, so a lane's numbers are the scalar code's on every x86-64 machine.
using V2 = double __attribute__((vector_size(16)));
using V4 = double __attribute__((vector_size(32)));
template <int D>
using Lanes = std::conditional_t<D == 2, V2, V4>;

/// The interpolated values at P points (x: P x D coordinates, out likewise). Per point the sum
/// over the 4^D stencil nodes in order, acc += w * value, with w = (w_z w_y) w_x, a node's D
/// components side by side in one register (in 3D a fourth lane, the next entry, is carried and
/// dropped); the P points' sums are interleaved, so that their additions, each waiting on the
/// one before, overlap.
template <int D, int P>
[[gnu::always_inline]] inline void evaluate_points(const Grid& g, const double* values, const double* x, double* out) {
  using V = Lanes<D>;
  int ix[P][3][4];
  double wx[P][3][4];
  for (int p = 0; p < P; ++p)
    for (int a = 0; a < 3; ++a)
      stencil(a < D ? x[p * D + a] : 0.0, g.lower[a], g.spacing, g.n[a], ix[p][a], wx[p][a]);
  const std::int64_t s1 = g.n[0], s2 = std::int64_t(g.n[0]) * g.n[1];
  V acc[P];
  for (int p = 0; p < P; ++p) acc[p] = V{};
  const int kz = D == 3 ? 4 : 1;
  for (int c = 0; c < kz; ++c)
    for (int b = 0; b < 4; ++b) {
      double wyz[P];
      const double* row[P];
      for (int p = 0; p < P; ++p) {
        const double wz = D == 3 ? wx[p][2][c] : 1.0;
        wyz[p] = wz * wx[p][1][b];
        row[p] = values + D * ((D == 3 ? ix[p][2][c] * s2 : 0) + ix[p][1][b] * s1);
      }
#pragma GCC unroll 4
      for (int a = 0; a < 4; ++a)
        for (int p = 0; p < P; ++p) {
          const double w = wyz[p] * wx[p][0][a];
          V v;
          std::memcpy(&v, row[p] + D * ix[p][0][a], sizeof v);
          acc[p] += w * v;
        }
    }
  for (int p = 0; p < P; ++p)
    for (int d = 0; d < D; ++d) out[p * D + d] = acc[p][d];
}

template <int D>
[[gnu::always_inline]] inline void evaluate_all(const Grid& g, const double* values, std::size_t n, const double* x,
                                                double* out) {
  std::size_t i = 0;
  for (; i + 4 <= n; i += 4) evaluate_points<D, 4>(g, values, x + i * D, out + i * D);
  for (; i < n; ++i) evaluate_points<D, 1>(g, values, x + i * D, out + i * D);
}

void evaluate_2d(const Grid& g, const double* values, std::size_t n, const double* x, double* out) {
  evaluate_all<2>(g, values, n, x, out);
}

/// Compiled twice, for AVX2 (without FMA) and for the baseline, the one the CPU runs chosen at
/// load time.
[[gnu::target_clones("avx2", "default")]] void evaluate_3d(const Grid& g, const double* values, std::size_t n,
                                                           const double* x, double* out) {
  evaluate_all<3>(g, values, n, x, out);
}

/// Symmetric square root factor A (A A^T = C) of the 1D kernel matrix
/// C_ij = exp(-(x_i - x_j)^2 / (2 sigma^2)). Eigenvalues that round-off makes slightly negative
/// are set to zero (the matrix is positive semi-definite in exact arithmetic).
Eigen::MatrixXd kernel_factor(int n, double spacing, double sigma) {
  Eigen::MatrixXd c(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const double d = (i - j) * spacing;
      c(i, j) = std::exp(-d * d / (2.0 * sigma * sigma));
    }
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(c);
  const Eigen::VectorXd root = eig.eigenvalues().cwiseMax(0.0).cwiseSqrt();
  return eig.eigenvectors() * root.asDiagonal();
}

/// kernel_factor(n, spacing, sigma), computed once per process for each (n, spacing, sigma): a
/// shape's grids are of a few sizes (each deformation step works in the box [-1, 1]^d of the
/// step before, so its longest axis has the same node count on every shape), and the
/// eigendecomposition was a twentieth of a Random2D shape's work (callgrind). The same numbers:
/// a factor is the same computation's result. At most kMaxBytes are kept (the oldest dropped).
std::shared_ptr<const Eigen::MatrixXd> cached_kernel_factor(int n, double spacing, double sigma) {
  using Key = std::tuple<int, double, double>;
  static std::mutex mutex;
  static std::map<Key, std::shared_ptr<const Eigen::MatrixXd>> cache;
  static std::deque<Key> order;
  static std::size_t bytes = 0;
  constexpr std::size_t kMaxBytes = std::size_t(64) << 20;
  const Key key{n, spacing, sigma};
  std::lock_guard<std::mutex> lock(mutex);
  if (const auto it = cache.find(key); it != cache.end()) return it->second;
  auto a = std::make_shared<const Eigen::MatrixXd>(kernel_factor(n, spacing, sigma));
  const std::size_t size = std::size_t(n) * std::size_t(n) * sizeof(double);
  while (!order.empty() && bytes + size > kMaxBytes) {
    bytes -= std::size_t(cache.at(order.front())->size()) * sizeof(double);
    cache.erase(order.front());
    order.pop_front();
  }
  cache.emplace(key, a);
  order.push_back(key);
  bytes += size;
  return a;
}

}  // namespace

void GridField::evaluate(const double* x, double* value) const { evaluate(1, x, value); }

void GridField::evaluate(std::size_t n, const double* x, double* values) const {
  (grid_.dim == 2 ? evaluate_2d : evaluate_3d)(grid_, values_.data(), n, x, values);
}

double GridField::max_norm() const {
  const std::int64_t n = grid_.n_nodes();
  double m2 = 0.0;
  for (std::int64_t i = 0; i < n; ++i) {
    double s = 0.0;
    for (int d = 0; d < grid_.dim; ++d) s += at(i, d) * at(i, d);
    m2 = std::max(m2, s);
  }
  return std::sqrt(m2);
}

GridField sample_velocity_field(const Grid& grid, double sigma, double m,
                                core::RandomStream& rng) {
  assert(sigma > 0.0);
  GridField field(grid);
  const int n0 = grid.n[0], n1 = grid.n[1], n2 = grid.n[2];
  const auto f0 = cached_kernel_factor(n0, grid.spacing, sigma);
  const auto f1 = cached_kernel_factor(n1, grid.spacing, sigma);
  const auto f2 = grid.dim == 3 ? cached_kernel_factor(n2, grid.spacing, sigma)
                                : std::make_shared<const Eigen::MatrixXd>(Eigen::MatrixXd::Identity(1, 1));
  const Eigen::MatrixXd &a0 = *f0, &a1 = *f1, &a2 = *f2;
  using Map = Eigen::Map<Eigen::MatrixXd>;
  const std::int64_t n = grid.n_nodes();
  std::vector<double> v(static_cast<std::size_t>(n));  // one component, node by node
  for (int c = 0; c < grid.dim; ++c) {
    for (double& xi : v) xi = rng.normal();
    // Axis 0: the node array as an n0 x (n1 n2) column-major matrix.
    Map m0(v.data(), n0, std::int64_t(n1) * n2);
    m0 = (a0 * m0).eval();
    // Axis 1: each z-slab is an n0 x n1 matrix.
    for (int k = 0; k < n2; ++k) {
      Map slab(v.data() + std::int64_t(k) * n0 * n1, n0, n1);
      slab = (slab * a1.transpose()).eval();
    }
    // Axis 2: the array as an (n0 n1) x n2 matrix.
    if (grid.dim == 3) {
      Map m2(v.data(), std::int64_t(n0) * n1, n2);
      m2 = (m2 * a2.transpose()).eval();
    }
    for (std::int64_t i = 0; i < n; ++i) field.at(i, c) = v[std::size_t(i)] * m;
  }
  return field;
}

GridField exponentiate(GridField v, int n_squarings) {
  assert(n_squarings >= 0);
  const Grid g = v.grid();
  const int dim = g.dim;
  const std::int64_t n = g.n_nodes();
  const double tau = std::ldexp(1.0, -n_squarings);
  GridField u(g);
  // A sweep over the nodes, in chunks: the chunk's points y(node), the field f at all of them in
  // one call, then store(node, f(y)).
  constexpr std::int64_t chunk = 256;
  std::vector<double> y(std::size_t(chunk * dim)), fy(y.size());
  const auto sweep = [&](const GridField& f, auto&& point, auto&& store) {
    double x[3];
    int ijk[3] = {0, 0, 0};  // node (i0 + i)'s lattice indices, counted up (node_coords without divisions)
    for (std::int64_t i0 = 0; i0 < n; i0 += chunk) {
      const std::int64_t m = std::min(chunk, n - i0);
      for (std::int64_t i = 0; i < m; ++i) {
        for (int a = 0; a < dim; ++a) x[a] = g.lower[a] + double(ijk[a]) * g.spacing;
        point(i0 + i, x, &y[std::size_t(i * dim)]);
        for (int a = 0; a < 3 && ++ijk[a] == g.n[a]; ++a) ijk[a] = 0;
      }
      f.evaluate(std::size_t(m), y.data(), fy.data());
      for (std::int64_t i = 0; i < m; ++i) store(i0 + i, &fy[std::size_t(i * dim)]);
    }
  };
  // Midpoint step: u_0(x) = tau v(x + tau v(x) / 2).
  sweep(
      v, [&](std::int64_t i, const double* x, double* yi) {
        for (int d = 0; d < dim; ++d) yi[d] = x[d] + 0.5 * tau * v.at(i, d);
      },
      [&](std::int64_t i, const double* w) {
        for (int d = 0; d < dim; ++d) u.at(i, d) = tau * w[d];
      });
  // Squarings: phi <- phi o phi, i.e. u(x) <- u(x) + u(x + u(x)); v's storage is reused.
  GridField next = std::move(v);
  for (int s = 0; s < n_squarings; ++s) {
    sweep(
        u, [&](std::int64_t i, const double* x, double* yi) {
          for (int d = 0; d < dim; ++d) yi[d] = x[d] + u.at(i, d);
        },
        [&](std::int64_t i, const double* w) {
          for (int d = 0; d < dim; ++d) next.at(i, d) = u.at(i, d) + w[d];
        });
    std::swap(u, next);
  }
  return u;
}

int default_squarings(const GridField& v) {
  const double vmax = v.max_norm();
  int n = 0;
  while (std::ldexp(vmax, -n) > v.grid().spacing / 8.0 && n < 30) ++n;
  return n;
}

}  // namespace hypershape::geometry
