// The paper's discrete metrics (sampling::NodalNorms, discrete_l2_norm): the recovered nodal
// gradient is exact for fields the space contains (linear on P1, quadratic on P2, in 2D and
// 3D, on structured simplex meshes built here), norms of known fields, relative errors of
// scaled fields, and bad input. The agreement with scripts/hypershape_data.py (the Python
// implementation) to round-off on a real solution is checked by tests/cli/test_study_accuracy.sh.
#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <functional>
#include <map>
#include <stdexcept>
#include <utility>
#include <vector>

#include "hypershape/sampling/field_error.hpp"

namespace hs = hypershape::sampling;

namespace {

struct Mesh {
  int dim = 2, per_cell = 3;
  std::vector<double> nodes;
  std::vector<std::int64_t> cells;
  std::size_t n_nodes() const { return nodes.size() / std::size_t(dim); }
};

/// [0, 1]^2 cut into n x n squares, two triangles each (a slight shear keeps it irregular).
Mesh square(int n) {
  Mesh m;
  m.dim = 2;
  m.per_cell = 3;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const double x = double(i) / n, y = double(j) / n;
      m.nodes.push_back(x + 0.1 * y * (1 - y) * x * (1 - x));
      m.nodes.push_back(y);
    }
  auto id = [n](int i, int j) { return std::int64_t(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      m.cells.insert(m.cells.end(), {id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.cells.insert(m.cells.end(), {id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return m;
}

/// [0, 1]^3 cut into n^3 cubes, six tetrahedra each (Kuhn).
Mesh cube(int n) {
  Mesh m;
  m.dim = 3;
  m.per_cell = 4;
  for (int k = 0; k <= n; ++k)
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i)
        m.nodes.insert(m.nodes.end(), {double(i) / n, double(j) / n, double(k) / n});
  auto id = [n](int i, int j, int k) { return std::int64_t((k * (n + 1) + j) * (n + 1) + i); };
  static const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        for (const auto& p : perms) {
          std::array<int, 3> c{i, j, k};
          std::vector<std::int64_t> t{id(c[0], c[1], c[2])};
          for (int s = 0; s < 3; ++s) {
            c[std::size_t(p[s])] += 1;
            t.push_back(id(c[0], c[1], c[2]));
          }
          m.cells.insert(m.cells.end(), t.begin(), t.end());
        }
  return m;
}

/// The P2 mesh: one midpoint node per edge after the vertices, VTK order.
Mesh p2(const Mesh& p1) {
  Mesh m = p1;
  const int d = p1.dim, nv = d + 1;
  static const int tri[3][2] = {{0, 1}, {1, 2}, {2, 0}};
  static const int tet[6][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};
  const int ne = d == 2 ? 3 : 6;
  m.per_cell = nv + ne;
  m.cells.clear();
  std::map<std::pair<std::int64_t, std::int64_t>, std::int64_t> mid;
  for (std::size_t c = 0; c < p1.cells.size(); c += std::size_t(nv)) {
    std::vector<std::int64_t> cell(p1.cells.begin() + std::ptrdiff_t(c), p1.cells.begin() + std::ptrdiff_t(c) + nv);
    for (int e = 0; e < ne; ++e) {
      const auto a = cell[std::size_t(d == 2 ? tri[e][0] : tet[e][0])];
      const auto b = cell[std::size_t(d == 2 ? tri[e][1] : tet[e][1])];
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      auto it = mid.find(key);
      if (it == mid.end()) {
        it = mid.emplace(key, std::int64_t(m.n_nodes())).first;
        for (int k = 0; k < d; ++k)
          m.nodes.push_back(0.5 * (p1.nodes[std::size_t(a * d + k)] + p1.nodes[std::size_t(b * d + k)]));
      }
      cell.push_back(it->second);
    }
    m.cells.insert(m.cells.end(), cell.begin(), cell.end());
  }
  return m;
}

using Fn = std::function<void(const double*, double*, double*)>;  // x -> u (2), grad (2 x dim)

std::vector<double> sample(const Mesh& m, const Fn& f, std::vector<double>* grad = nullptr) {
  std::vector<double> u(m.n_nodes() * 2);
  if (grad) grad->assign(m.n_nodes() * 2 * std::size_t(m.dim), 0.0);
  std::vector<double> g(2 * std::size_t(m.dim));
  for (std::size_t i = 0; i < m.n_nodes(); ++i) {
    f(&m.nodes[i * std::size_t(m.dim)], &u[2 * i], g.data());
    if (grad) std::copy(g.begin(), g.end(), grad->begin() + std::ptrdiff_t(i * g.size()));
  }
  return u;
}

double max_abs_diff(const std::vector<double>& a, const std::vector<double>& b) {
  double m = 0;
  for (std::size_t i = 0; i < a.size(); ++i) m = std::max(m, std::abs(a[i] - b[i]));
  return m;
}

// Linear and quadratic fields with two components, with their exact gradients.
void linear(int d, const double* x, double* u, double* g) {
  const double z = d == 3 ? x[2] : 0.0;
  u[0] = 1 + 2 * x[0] - 3 * x[1] + 0.5 * z;
  u[1] = -x[0] + 4 * x[1] - z;
  const double gg[2][3] = {{2, -3, 0.5}, {-1, 4, -1}};
  for (int c = 0; c < 2; ++c)
    for (int k = 0; k < d; ++k) g[c * d + k] = gg[c][k];
}
void quadratic(int d, const double* x, double* u, double* g) {
  const double z = d == 3 ? x[2] : 0.0;
  u[0] = x[0] * x[0] - 2 * x[0] * x[1] + 0.3 * z * z + x[1];
  u[1] = x[1] * x[1] + x[0] * z - 0.5 * x[0];
  const double gg[2][3] = {{2 * x[0] - 2 * x[1], -2 * x[0] + 1, 0.6 * z}, {z - 0.5, 2 * x[1], x[0]}};
  for (int c = 0; c < 2; ++c)
    for (int k = 0; k < d; ++k) g[c * d + k] = gg[c][k];
}

}  // namespace

TEST_CASE("NodalNorms: the recovered gradient is exact for fields the space contains",
          "[sampling][field_error]") {
  for (const Mesh& p1m : {square(5), cube(2)}) {
    const int d = p1m.dim;
    INFO("dim " << d);
    {
      std::vector<double> g_exact;
      const auto u = sample(p1m, [d](const double* x, double* v, double* g) { linear(d, x, v, g); }, &g_exact);
      const hs::NodalNorms nn(d, p1m.nodes, p1m.cells, p1m.per_cell);
      CHECK(max_abs_diff(nn.gradient(u, 2), g_exact) < 1e-12);
    }
    const Mesh p2m = p2(p1m);
    for (bool quad : {false, true}) {
      std::vector<double> g_exact;
      const auto u = sample(
          p2m, [d, quad](const double* x, double* v, double* g) { quad ? quadratic(d, x, v, g) : linear(d, x, v, g); },
          &g_exact);
      const hs::NodalNorms nn(d, p2m.nodes, p2m.cells, p2m.per_cell);
      CHECK(max_abs_diff(nn.gradient(u, 2), g_exact) < 1e-11);
    }
    // A quadratic field on P1 is not exact: the recovered gradient differs (but stays close).
    std::vector<double> g_exact;
    const auto u = sample(p1m, [d](const double* x, double* v, double* g) { quadratic(d, x, v, g); }, &g_exact);
    const hs::NodalNorms nn(d, p1m.nodes, p1m.cells, p1m.per_cell);
    const double diff = max_abs_diff(nn.gradient(u, 2), g_exact);
    CHECK(diff > 1e-6);
    CHECK(diff < 1.5);
  }
}

TEST_CASE("NodalNorms: norms of known fields and relative errors", "[sampling][field_error]") {
  const Mesh m = p2(square(4));
  const hs::NodalNorms nn(2, m.nodes, m.cells, m.per_cell);
  const std::size_t n = m.n_nodes();
  // u = (x, 2y): ||u||_L2^2 = mean(x^2 + 4 y^2); |grad u|^2 = 1 + 4 at every node.
  std::vector<double> u(2 * n), twice(2 * n), zero(2 * n, 0.0);
  double s = 0;
  for (std::size_t i = 0; i < n; ++i) {
    u[2 * i] = m.nodes[2 * i];
    u[2 * i + 1] = 2 * m.nodes[2 * i + 1];
    s += u[2 * i] * u[2 * i] + u[2 * i + 1] * u[2 * i + 1];
    twice[2 * i] = 2 * u[2 * i];
    twice[2 * i + 1] = 2 * u[2 * i + 1];
  }
  CHECK(hs::discrete_l2_norm(u, 2) == Approx(std::sqrt(s / double(n))).epsilon(1e-14));
  CHECK(nn.h1_norm(u, 2) == Approx(std::sqrt(s / double(n) + 5.0)).epsilon(1e-12));
  CHECK(nn.rel_l2(u, u, 2) == 0.0);
  CHECK(nn.rel_h1(u, u, 2) == 0.0);
  CHECK(nn.rel_l2(u, twice, 2) == Approx(1.0).epsilon(1e-14));
  CHECK(nn.rel_h1(u, twice, 2) == Approx(1.0).epsilon(1e-12));
  CHECK(nn.rel_l2(u, zero, 2) == Approx(1.0).epsilon(1e-14));
  // A constant field has zero gradient: H1 = L2.
  std::vector<double> c(2 * n, 0.7);
  CHECK(nn.h1_norm(c, 2) == Approx(hs::discrete_l2_norm(c, 2)).epsilon(1e-12));
  // One component, scalar field.
  std::vector<double> x(n);
  for (std::size_t i = 0; i < n; ++i) x[i] = m.nodes[2 * i];
  const auto gx = nn.gradient(x, 1);
  for (std::size_t i = 0; i < n; ++i) {
    CHECK(gx[2 * i] == Approx(1.0).epsilon(1e-12));
    CHECK(std::abs(gx[2 * i + 1]) < 1e-12);
  }
}

TEST_CASE("NodalNorms rejects bad input", "[sampling][field_error]") {
  const Mesh m = square(2);
  CHECK_THROWS_AS(hs::NodalNorms(4, m.nodes, m.cells, 3), std::invalid_argument);
  CHECK_THROWS_AS(hs::NodalNorms(2, m.nodes, m.cells, 5), std::invalid_argument);
  CHECK_THROWS_AS(hs::NodalNorms(2, m.nodes, std::vector<std::int64_t>{0, 1}, 3), std::invalid_argument);
  CHECK_THROWS_AS(hs::NodalNorms(2, m.nodes, std::vector<std::int64_t>{0, 1, 99}, 3), std::invalid_argument);
  CHECK_THROWS_AS(hs::NodalNorms(2, m.nodes, std::vector<std::int64_t>{0, 1, 2}, 3), std::invalid_argument);  // collinear
  const hs::NodalNorms nn(2, m.nodes, m.cells, 3);
  CHECK_THROWS_AS(nn.gradient(std::vector<double>(5, 0.0), 2), std::invalid_argument);
  CHECK_THROWS_AS(nn.rel_l2(std::vector<double>(18, 1.0), std::vector<double>(17, 1.0), 2), std::invalid_argument);
  CHECK_THROWS_AS(hs::discrete_l2_norm(std::vector<double>(5, 0.0), 2), std::invalid_argument);
}
