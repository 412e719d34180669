#include "hypershape/mesh/refine.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>

namespace hypershape::mesh {

namespace {

/// Signed measure (up to a positive factor) of the simplex with vertices x[0..d].
double orientation(int d, const std::array<std::array<double, 3>, 4>& x) {
  double e[3][3];
  for (int i = 0; i < d; ++i)
    for (int k = 0; k < d; ++k) e[i][k] = x[i + 1][k] - x[0][k];
  if (d == 2) return e[0][0] * e[1][1] - e[0][1] * e[1][0];
  return e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) - e[0][1] * (e[1][0] * e[2][2] - e[1][2] * e[2][0]) +
         e[0][2] * (e[1][0] * e[2][1] - e[1][1] * e[2][0]);
}

/// Children as local node lists: 0..d the parent's vertices, d+1.. the midpoints of the parent's
/// edges in the order of `pair` below.
using Child = std::array<int, 4>;

/// The children of a cell whose local nodes (vertices, then edge midpoints) are at x. 2D: m01 =
/// 3, m12 = 4, m02 = 5. 3D: m01 = 4, m12 = 5, m02 = 6, m03 = 7, m13 = 8, m23 = 9; the four
/// corner tetrahedra and the octahedron m01 m12 m02 m03 m13 m23 cut along its shortest diagonal
/// (the best-shaped inner tetrahedra), the four tetrahedra around it.
std::vector<Child> children_of(int d, const std::array<std::array<double, 3>, 10>& x) {
  static const std::vector<Child> c2{{0, 3, 5, 0}, {3, 1, 4, 0}, {5, 4, 2, 0}, {3, 4, 5, 0}};
  static const std::vector<Child> corners3{{0, 4, 6, 7}, {4, 1, 5, 8}, {6, 5, 2, 9}, {7, 8, 9, 3}};
  // The three diagonals (m01-m23, m12-m03, m02-m13), each with the ring around it.
  static const std::array<std::array<int, 6>, 3> diagonals{{{4, 9, 5, 6, 7, 8},    // m01-m23; ring m12 m02 m03 m13
                                                            {5, 7, 4, 6, 9, 8},    // m12-m03; ring m01 m02 m23 m13
                                                            {6, 8, 4, 5, 9, 7}}};  // m02-m13; ring m01 m12 m23 m03
  if (d == 2) return c2;
  std::vector<Child> children = corners3;
  double best = 1e300;
  std::size_t pick = 0;
  for (std::size_t i = 0; i < diagonals.size(); ++i) {
    double l2 = 0;
    for (int k = 0; k < 3; ++k) l2 += std::pow(x[std::size_t(diagonals[i][0])][std::size_t(k)] - x[std::size_t(diagonals[i][1])][std::size_t(k)], 2);
    if (l2 < best) best = l2, pick = i;
  }
  const auto& g = diagonals[pick];
  for (int r = 0; r < 4; ++r) children.push_back({g[0], g[1], g[2 + r], g[2 + (r + 1) % 4]});
  return children;
}

}  // namespace

RefinedMesh refine_uniform(const MeshData& coarse) {
  const int d = coarse.dim;
  if (d != 2 && d != 3) throw std::invalid_argument("refine_uniform: dim must be 2 or 3");
  const int nv = d + 1;
  RefinedMesh out;
  out.n_coarse_vertices = coarse.n_vertices();
  out.mesh.dim = d;
  out.mesh.coords = coarse.coords;
  out.coarse_cells = coarse.cells;
  // Local edges (a, b) in local node numbers (vertices 0..d, midpoints d+1..).
  static const std::vector<std::pair<int, int>> e2{{0, 1}, {1, 2}, {0, 2}};
  static const std::vector<std::pair<int, int>> e3{{0, 1}, {1, 2}, {0, 2}, {0, 3}, {1, 3}, {2, 3}};
  const auto& pair = d == 2 ? e2 : e3;
  std::map<std::pair<int, int>, int> midpoint;
  auto mid = [&](int a, int b) {
    const auto key = std::minmax(a, b);
    auto [it, fresh] = midpoint.try_emplace({key.first, key.second}, int(out.mesh.coords.size() / std::size_t(d)));
    if (fresh)
      for (int k = 0; k < d; ++k)
        out.mesh.coords.push_back(0.5 * (coarse.coords[std::size_t(a * d + k)] + coarse.coords[std::size_t(b * d + k)]));
    return it->second;
  };
  const std::int64_t n_cells = coarse.n_cells();
  for (std::int64_t c = 0; c < n_cells; ++c) {
    const int* v = &coarse.cells[std::size_t(c * nv)];
    int node[10];
    std::array<std::array<double, 4>, 10> lam{};  // barycentric of each local node
    std::array<std::array<double, 3>, 10> x{};
    for (int a = 0; a < nv; ++a) {
      node[a] = v[a];
      lam[std::size_t(a)][std::size_t(a)] = 1.0;
    }
    for (std::size_t e = 0; e < pair.size(); ++e) {
      const auto [a, b] = pair[e];
      node[nv + int(e)] = mid(v[a], v[b]);
      for (int k = 0; k < nv; ++k) lam[nv + e][std::size_t(k)] = 0.5 * (lam[std::size_t(a)][std::size_t(k)] + lam[std::size_t(b)][std::size_t(k)]);
    }
    for (int a = 0; a < nv + int(pair.size()); ++a)
      for (int k = 0; k < d; ++k) x[std::size_t(a)][std::size_t(k)] = out.mesh.coords[std::size_t(node[a] * d + k)];
    const std::vector<Child> children = children_of(d, x);
    std::array<std::array<double, 3>, 4> px{};
    for (int a = 0; a < nv; ++a) px[std::size_t(a)] = x[std::size_t(a)];
    const bool positive = orientation(d, px) > 0;
    for (Child ch : children) {
      std::array<std::array<double, 3>, 4> cx{};
      for (int a = 0; a < nv; ++a) cx[std::size_t(a)] = x[std::size_t(ch[std::size_t(a)])];
      if ((orientation(d, cx) > 0) != positive) std::swap(ch[0], ch[1]);
      out.parent.push_back(c);
      for (int a = 0; a < nv; ++a) {
        out.mesh.cells.push_back(node[ch[std::size_t(a)]]);
        for (int k = 0; k < nv; ++k) out.bary.push_back(lam[std::size_t(ch[std::size_t(a)])][std::size_t(k)]);
      }
    }
  }
  return out;
}

}  // namespace hypershape::mesh
