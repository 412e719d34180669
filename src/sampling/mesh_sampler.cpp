#include "hypershape/sampling/mesh_sampler.hpp"
#include "hypershape/mesh/reference_cell.hpp"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace hypershape::sampling {
namespace {

// Barycentric tolerances. A point whose smallest barycentric coordinate in a cell is above
// kInside is in that cell beyond round-off. One within kNear of a cell (but not beyond kInside)
// is decided by the exact side test: the round-off of barycentric coordinates is about
// 1e-16 * (condition number of the cell), so kNear leaves room for cells of condition 1e9.
constexpr double kInside = 1e-10;
constexpr double kNear = 1e-6;

[[noreturn]] void fail(const std::string& what) {
  throw std::invalid_argument("MeshSampler: " + what);
}

using mesh::edge_node;
using mesh::nodes_per_cell;

/// Lagrange basis at barycentric coordinates `l` (dim + 1 of them): P1 or P2 in VTK order.
void cell_basis(int dim, int degree, const double* l, double* w) {
  const int nv = dim + 1;
  if (degree == 1) {
    for (int i = 0; i < nv; ++i) w[i] = l[i];
    return;
  }
  for (int i = 0; i < nv; ++i) w[i] = l[i] * (2 * l[i] - 1);
  w[nv + 0] = 4 * l[0] * l[1];
  w[nv + 1] = 4 * l[1] * l[2];
  w[nv + 2] = 4 * l[2] * l[0];
  if (dim == 3) {
    w[7] = 4 * l[0] * l[3];
    w[8] = 4 * l[1] * l[3];
    w[9] = 4 * l[2] * l[3];
  }
}

/// Lagrange basis on a boundary facet (segment a b: a b m_ab; triangle a b c: a b c m_ab m_bc
/// m_ca) at barycentric coordinates `m` (dim of them).
void facet_basis(int dim, int degree, const double* m, double* w) {
  if (degree == 1) {
    for (int i = 0; i < dim; ++i) w[i] = m[i];
    return;
  }
  for (int i = 0; i < dim; ++i) w[i] = m[i] * (2 * m[i] - 1);
  if (dim == 2) {
    w[2] = 4 * m[0] * m[1];
  } else {
    w[3] = 4 * m[0] * m[1];
    w[4] = 4 * m[1] * m[2];
    w[5] = 4 * m[2] * m[0];
  }
}

/// Clamps barycentric coordinates to >= 0 and rescales them to sum 1.
void clamp_barycentric(double* l, int n) {
  double sum = 0;
  for (int i = 0; i < n; ++i) sum += (l[i] = std::max(l[i], 0.0));
  if (!(sum > 0)) {
    for (int i = 0; i < n; ++i) l[i] = i == 0 ? 1.0 : 0.0;
    return;
  }
  for (int i = 0; i < n; ++i) l[i] /= sum;
}

/// Per-cell affine data for barycentric coordinates: v0 and the inverse of J = [v1-v0 ... vd-v0],
/// so that (l1..ld) = J^{-1} (x - v0), l0 = 1 - sum.
class CellMaps {
 public:
  CellMaps(int dim, std::span<const double> nodes, std::span<const std::int64_t> cells, int npc)
      : dim_(dim), stride_(dim + dim * dim) {
    const std::size_t n_cells = cells.size() / std::size_t(npc);
    data_.resize(n_cells * std::size_t(stride_));
    valid_.assign(n_cells, 0);
    const std::size_t d = std::size_t(dim);
    for (std::size_t c = 0; c < n_cells; ++c) {
      const std::int64_t* v = cells.data() + c * std::size_t(npc);
      double* m = data_.data() + c * std::size_t(stride_);
      const double* x0 = nodes.data() + std::size_t(v[0]) * d;
      for (std::size_t k = 0; k < d; ++k) m[k] = x0[k];
      double J[3][3];  // J[r][s]: component r of v_{s+1} - v0
      for (std::size_t s = 0; s < d; ++s) {
        const double* xs = nodes.data() + std::size_t(v[s + 1]) * d;
        for (std::size_t r = 0; r < d; ++r) J[r][s] = xs[r] - x0[r];
      }
      double* inv = m + d;  // row-major d x d
      double det;
      if (dim == 2) {
        det = J[0][0] * J[1][1] - J[0][1] * J[1][0];
        inv[0] = J[1][1] / det;
        inv[1] = -J[0][1] / det;
        inv[2] = -J[1][0] / det;
        inv[3] = J[0][0] / det;
      } else {
        const double c00 = J[1][1] * J[2][2] - J[1][2] * J[2][1];
        const double c01 = J[1][2] * J[2][0] - J[1][0] * J[2][2];
        const double c02 = J[1][0] * J[2][1] - J[1][1] * J[2][0];
        det = J[0][0] * c00 + J[0][1] * c01 + J[0][2] * c02;
        inv[0] = c00 / det;
        inv[1] = (J[0][2] * J[2][1] - J[0][1] * J[2][2]) / det;
        inv[2] = (J[0][1] * J[1][2] - J[0][2] * J[1][1]) / det;
        inv[3] = c01 / det;
        inv[4] = (J[0][0] * J[2][2] - J[0][2] * J[2][0]) / det;
        inv[5] = (J[0][2] * J[1][0] - J[0][0] * J[1][2]) / det;
        inv[6] = c02 / det;
        inv[7] = (J[0][1] * J[2][0] - J[0][0] * J[2][1]) / det;
        inv[8] = (J[0][0] * J[1][1] - J[0][1] * J[1][0]) / det;
      }
      bool ok = det != 0 && std::isfinite(det);
      for (std::size_t k = 0; k < d * d; ++k) ok = ok && std::isfinite(inv[k]);
      valid_[c] = ok;
    }
  }

  bool valid(std::size_t c) const { return valid_[c] != 0; }

  /// Barycentric coordinates of x in cell c (dim + 1 values); returns the smallest.
  double barycentric(std::size_t c, const double* x, double* l) const {
    const double* m = data_.data() + c * std::size_t(stride_);
    const double* inv = m + dim_;
    if (dim_ == 2) {
      const double y0 = x[0] - m[0], y1 = x[1] - m[1];
      l[1] = inv[0] * y0 + inv[1] * y1;
      l[2] = inv[2] * y0 + inv[3] * y1;
      l[0] = 1 - l[1] - l[2];
      return std::min({l[0], l[1], l[2]});
    }
    const double y0 = x[0] - m[0], y1 = x[1] - m[1], y2 = x[2] - m[2];
    l[1] = inv[0] * y0 + inv[1] * y1 + inv[2] * y2;
    l[2] = inv[3] * y0 + inv[4] * y1 + inv[5] * y2;
    l[3] = inv[6] * y0 + inv[7] * y1 + inv[8] * y2;
    l[0] = 1 - l[1] - l[2] - l[3];
    return std::min({l[0], l[1], l[2], l[3]});
  }

 private:
  int dim_, stride_;
  std::vector<double> data_;
  std::vector<std::uint8_t> valid_;
};

/// Uniform buckets over the bounding box of the cells; each cell is listed in every bucket its
/// (slightly enlarged) bounding box meets.
class CellBuckets {
 public:
  CellBuckets(int dim, std::span<const double> nodes, std::span<const std::int64_t> cells, int npc,
              const CellMaps& maps)
      : dim_(dim) {
    const std::size_t n_cells = cells.size() / std::size_t(npc);
    double mean_extent = 0;
    std::size_t n_valid = 0;
    const std::vector<double> boxes = cell_boxes(nodes, cells, npc, maps, mean_extent, n_valid);
    set_grid(mean_extent, n_valid);
    fill(boxes, n_cells, maps);
  }

  /// The cells listed in x's bucket (empty outside the bounding box).
  std::span<const std::int32_t> candidates(const double* x) const {
    std::array<int, 3> i{0, 0, 0};
    for (std::size_t k = 0; k < std::size_t(dim_); ++k) {
      if (!(x[k] >= lo_[k] && x[k] <= hi_[k])) return {};
      i[k] = index(x[k], k);
    }
    const std::size_t b = flat(i[0], i[1], i[2]);
    return {items_.data() + start_[b], std::size_t(start_[b + 1] - start_[b])};
  }

 private:
  /// Per cell its bounding box (min (d), max (d)), enlarged so that points with barycentric
  /// coordinates down to -kNear are found; lo_/hi_ their union; the mean extent and number of
  /// the valid cells.
  std::vector<double> cell_boxes(std::span<const double> nodes, std::span<const std::int64_t> cells, int npc,
                                 const CellMaps& maps, double& mean_extent, std::size_t& n_valid) {
    const std::size_t d = std::size_t(dim_), n_cells = cells.size() / std::size_t(npc);
    std::vector<double> boxes(n_cells * 2 * d);
    lo_.fill(HUGE_VAL);
    hi_.fill(-HUGE_VAL);
    for (std::size_t c = 0; c < n_cells; ++c) {
      double* b = boxes.data() + c * 2 * d;
      for (std::size_t k = 0; k < d; ++k) b[k] = HUGE_VAL, b[d + k] = -HUGE_VAL;
      for (std::size_t i = 0; i <= d; ++i) {
        const double* x = nodes.data() + std::size_t(cells[c * std::size_t(npc) + i]) * d;
        for (std::size_t k = 0; k < d; ++k)
          b[k] = std::min(b[k], x[k]), b[d + k] = std::max(b[d + k], x[k]);
      }
      double extent = 0;
      for (std::size_t k = 0; k < d; ++k) extent = std::max(extent, b[d + k] - b[k]);
      for (std::size_t k = 0; k < d; ++k)
        b[k] -= 2 * kNear * extent, b[d + k] += 2 * kNear * extent;
      for (std::size_t k = 0; k < d; ++k)
        lo_[k] = std::min(lo_[k], b[k]), hi_[k] = std::max(hi_[k], b[d + k]);
      if (maps.valid(c)) mean_extent += extent, ++n_valid;
    }
    mean_extent = n_valid ? mean_extent / double(n_valid) : 1.0;
    return boxes;
  }

  /// Buckets of about the mean cell size (a few cells each), at most ~4 per cell.
  void set_grid(double mean_extent, std::size_t n_valid) {
    const std::size_t d = std::size_t(dim_);
    double h = mean_extent > 0 ? mean_extent : 1.0;
    for (;;) {
      double total = 1;
      for (std::size_t k = 0; k < d; ++k) total *= std::max(1.0, std::ceil((hi_[k] - lo_[k]) / h));
      if (total <= 4.0 * double(std::max<std::size_t>(n_valid, 1)) + 64) break;
      h *= 1.25;
    }
    for (std::size_t k = 0; k < d; ++k) {
      n_[k] = int(std::max(1.0, std::ceil((hi_[k] - lo_[k]) / h)));
      inv_h_[k] = 1.0 / h;
    }
  }

  /// Lists every valid cell in each bucket its box meets (counted, then filled: CSR).
  void fill(const std::vector<double>& boxes, std::size_t n_cells, const CellMaps& maps) {
    const std::size_t d = std::size_t(dim_);
    const std::size_t n_buckets = std::size_t(n_[0]) * std::size_t(n_[1]) * std::size_t(n_[2]);
    start_.assign(n_buckets + 1, 0);
    for (int pass = 0; pass < 2; ++pass) {
      std::vector<std::int64_t> next;
      if (pass == 1) {
        for (std::size_t b = 0; b < n_buckets; ++b) start_[b + 1] += start_[b];
        items_.resize(std::size_t(start_.back()));
        next.assign(start_.begin(), start_.end() - 1);
      }
      for (std::size_t c = 0; c < n_cells; ++c) {
        if (!maps.valid(c)) continue;
        const double* b = boxes.data() + c * 2 * d;
        std::array<int, 3> i0{0, 0, 0}, i1{0, 0, 0};
        for (std::size_t k = 0; k < d; ++k) {
          i0[k] = index(b[k], k);
          i1[k] = index(b[d + k], k);
        }
        for (int i = i0[0]; i <= i1[0]; ++i)
          for (int j = i0[1]; j <= i1[1]; ++j)
            for (int l = i0[2]; l <= i1[2]; ++l) {
              const std::size_t bucket = flat(i, j, l);
              if (pass == 0)
                ++start_[bucket + 1];
              else
                items_[std::size_t(next[bucket]++)] = std::int32_t(c);
            }
      }
    }
  }

  int index(double x, std::size_t k) const {
    const double s = std::floor((x - lo_[k]) * inv_h_[k]);
    return int(std::clamp(s, 0.0, double(n_[k] - 1)));
  }
  std::size_t flat(int i, int j, int l) const {
    return (std::size_t(i) * std::size_t(n_[1]) + std::size_t(j)) * std::size_t(n_[2]) +
           std::size_t(l);
  }

  int dim_;
  std::array<double, 3> lo_{}, hi_{}, inv_h_{1, 1, 1};
  std::array<int, 3> n_{1, 1, 1};
  std::vector<std::int64_t> start_;
  std::vector<std::int32_t> items_;
};

/// Sorts the first n (2 or 3) entries of a face key (a compare-swap network: std::sort on a
/// run-time length trips GCC's -Warray-bounds).
void sort_key(std::array<std::int64_t, 3>& k, int n) {
  const auto order = [&](int i, int j) {
    if (k[std::size_t(j)] < k[std::size_t(i)]) std::swap(k[std::size_t(i)], k[std::size_t(j)]);
  };
  order(0, 1);
  if (n == 3) {
    order(1, 2);
    order(0, 1);
  }
}

using FaceKey = std::array<std::int64_t, 3>;

/// Sorted vertex triples (third -1 in 2D) -> facet, sorted, for matching cell faces; which
/// points are facet vertices.
std::vector<std::pair<FaceKey, std::int64_t>> facet_keys(int dim, const geometry::Boundary& boundary,
                                                         std::vector<std::uint8_t>& on_boundary) {
  const std::int64_t n_facets = boundary.n_facets();
  std::vector<std::pair<FaceKey, std::int64_t>> keys;
  keys.reserve(std::size_t(n_facets));
  on_boundary.assign(std::size_t(boundary.n_points()), 0);
  for (std::int64_t f = 0; f < n_facets; ++f) {
    const auto v = boundary.facet(f);
    FaceKey k{v[0], v[1], dim == 3 ? v[2] : -1};
    sort_key(k, dim);
    keys.push_back({k, f});
    for (const int p : v) on_boundary[std::size_t(p)] = 1;
  }
  std::sort(keys.begin(), keys.end());
  return keys;
}

/// The stencil nodes of every boundary facet: its vertices (in the Boundary's order) and, for
/// P2, the midpoints of its edges (a b, b c, c a), read off the cell the facet belongs to.
/// Throws if a facet is not a face of any cell.
std::vector<std::int32_t> facet_nodes(int dim, int degree, std::span<const std::int64_t> cells,
                                      int npc, const geometry::Boundary& boundary) {
  const std::size_t d = std::size_t(dim);
  const std::int64_t n_facets = boundary.n_facets();
  const int fw = degree == 1 ? dim : (dim == 2 ? 3 : 6);
  std::vector<std::int32_t> out(std::size_t(n_facets) * std::size_t(fw), -1);

  std::vector<std::uint8_t> on_boundary;
  const std::vector<std::pair<FaceKey, std::int64_t>> keys = facet_keys(dim, boundary, on_boundary);
  using Key = FaceKey;
  std::vector<std::uint8_t> found(std::size_t(n_facets), 0);

  const std::size_t n_cells = cells.size() / std::size_t(npc);
  const std::int64_t n_bpoints = boundary.n_points();
  for (std::size_t c = 0; c < n_cells; ++c) {
    const std::int64_t* v = cells.data() + c * std::size_t(npc);
    for (std::size_t opposite = 0; opposite <= d; ++opposite) {
      // The face opposite local vertex `opposite`.
      Key k{-1, -1, -1};
      bool candidate = true;
      for (std::size_t i = 0, m = 0; i <= d; ++i) {
        if (i == opposite) continue;
        if (v[i] >= n_bpoints || !on_boundary[std::size_t(v[i])]) candidate = false;
        k[m++] = v[i];
      }
      if (!candidate) continue;
      sort_key(k, dim);
      auto it = std::lower_bound(keys.begin(), keys.end(), std::pair<Key, std::int64_t>{k, -1});
      for (; it != keys.end() && it->first == k; ++it) {
        const std::int64_t f = it->second;
        found[std::size_t(f)] = 1;
        const auto fv = boundary.facet(f);
        std::int32_t* o = out.data() + std::size_t(f) * std::size_t(fw);
        for (std::size_t i = 0; i < d; ++i) o[i] = std::int32_t(fv[i]);
        if (degree == 1) continue;
        const auto local = [&](int p) {
          for (int i = 0; i <= dim; ++i)
            if (v[i] == p) return i;
          return -1;  // unreachable: the face's vertices are the cell's
        };
        for (int e = 0; e < (dim == 2 ? 1 : 3); ++e) {
          const int a = local(fv[std::size_t(e)]), b = local(fv[std::size_t((e + 1) % dim)]);
          o[d + std::size_t(e)] = std::int32_t(v[edge_node(dim, a, b)]);
        }
      }
    }
  }
  for (std::int64_t f = 0; f < n_facets; ++f)
    if (!found[std::size_t(f)])
      fail("boundary facet " + std::to_string(f) + " is not a face of any cell");
  return out;
}

/// Barycentric coordinates (dim of them) of a point y on boundary facet f, clamped to the facet.
void facet_barycentric(const geometry::Boundary& boundary, std::int64_t f, const double* y,
                       double* m) {
  const int dim = boundary.dim;
  const auto v = boundary.facet(f);
  if (dim == 2) {
    const auto a = boundary.point(v[0]), b = boundary.point(v[1]);
    const double ab[2] = {b[0] - a[0], b[1] - a[1]};
    const double len2 = ab[0] * ab[0] + ab[1] * ab[1];
    const double t =
        len2 > 0 ? std::clamp(((y[0] - a[0]) * ab[0] + (y[1] - a[1]) * ab[1]) / len2, 0.0, 1.0)
                 : 0.0;
    m[0] = 1 - t;
    m[1] = t;
    return;
  }
  using V = std::array<double, 3>;
  const auto pt = [&](int i) {
    const auto p = boundary.point(i);
    return V{p[0], p[1], p[2]};
  };
  const auto sub = [](const V& p, const V& q) { return V{p[0] - q[0], p[1] - q[1], p[2] - q[2]}; };
  const auto cross = [](const V& p, const V& q) {
    return V{p[1] * q[2] - p[2] * q[1], p[2] * q[0] - p[0] * q[2], p[0] * q[1] - p[1] * q[0]};
  };
  const auto dot = [](const V& p, const V& q) { return p[0] * q[0] + p[1] * q[1] + p[2] * q[2]; };
  const V a = pt(v[0]), b = pt(v[1]), c = pt(v[2]), p{y[0], y[1], y[2]};
  const V n = cross(sub(b, a), sub(c, a));
  const double n2 = dot(n, n);
  if (!(n2 > 0)) {  // degenerate facets are never returned as closest; be safe anyway
    m[0] = 1, m[1] = 0, m[2] = 0;
    return;
  }
  // Signed sub-triangle areas relative to the whole (exact for p in the plane of abc).
  m[0] = dot(n, cross(sub(b, p), sub(c, p))) / n2;
  m[1] = dot(n, cross(sub(c, p), sub(a, p))) / n2;
  m[2] = 1 - m[0] - m[1];
  clamp_barycentric(m, 3);
}

}  // namespace

MeshSampler::MeshSampler(int dim, int degree, std::span<const double> nodes,
                         std::span<const std::int64_t> cells, const geometry::Boundary& boundary,
                         std::span<const double> points)
    : MeshSampler(
          dim, degree, nodes, cells, boundary,
          [&] {
            if (boundary.dim != dim)
              fail("boundary dimension " + std::to_string(boundary.dim) + " != mesh dimension " +
                   std::to_string(dim));
            return geometry::SignedDistance(boundary);
          }(),
          points) {}

MeshSampler::MeshSampler(int dim, int degree, std::span<const double> nodes,
                         std::span<const std::int64_t> cells, const geometry::Boundary& boundary,
                         const geometry::SignedDistance& distance, std::span<const double> points)
    : dim_(dim), degree_(degree) {
  validate(nodes, cells, boundary, distance, points);
  const std::vector<std::size_t> outside = locate(nodes, cells, distance, points);
  extend_from_boundary(outside, cells, boundary, distance, points);
}

void MeshSampler::validate(std::span<const double> nodes, std::span<const std::int64_t> cells,
                           const geometry::Boundary& boundary, const geometry::SignedDistance& distance,
                           std::span<const double> points) {
  const int dim = dim_, degree = degree_;
  if (dim != 2 && dim != 3) fail("dimension must be 2 or 3, got " + std::to_string(dim));
  if (degree != 1 && degree != 2) fail("degree must be 1 or 2, got " + std::to_string(degree));
  const std::size_t d = std::size_t(dim);
  const int npc = nodes_per_cell(dim, degree);
  width_ = npc;
  if (nodes.size() % d != 0) fail("node array size is not a multiple of the dimension");
  if (cells.empty() || cells.size() % std::size_t(npc) != 0)
    fail("cell array is empty or its size is not a multiple of " + std::to_string(npc));
  if (points.size() % d != 0) fail("point array size is not a multiple of the dimension");
  n_nodes_ = nodes.size() / d;
  n_points_ = points.size() / d;
  if (n_nodes_ >= std::size_t(std::numeric_limits<std::int32_t>::max())) fail("too many nodes for 32-bit stencils");
  for (const std::int64_t v : cells)
    if (v < 0 || std::size_t(v) >= n_nodes_)
      fail("cell refers to node " + std::to_string(v) + " of " + std::to_string(n_nodes_));
  for (const double x : nodes)
    if (!std::isfinite(x)) fail("non-finite node coordinate");
  for (const double x : points)
    if (!std::isfinite(x)) fail("non-finite point coordinate");
  if (boundary.dim != dim || distance.dim() != dim)
    fail("boundary dimension " + std::to_string(boundary.dim) + " != mesh dimension " + std::to_string(dim));
  if (std::size_t(boundary.n_points()) > n_nodes_) fail("boundary has more points than the mesh has nodes");
  double scale = 0;
  for (const double x : nodes) scale = std::max(scale, std::abs(x));
  for (std::size_t i = 0; i < boundary.points.size(); ++i)
    if (!(std::abs(boundary.points[i] - nodes[i]) <= 1e-12 * scale))
      fail("boundary point " + std::to_string(i / d) + " is not mesh vertex " + std::to_string(i / d));
}

std::vector<std::size_t> MeshSampler::locate(std::span<const double> nodes, std::span<const std::int64_t> cells,
                                             const geometry::SignedDistance& distance,
                                             std::span<const double> points) {
  const int dim = dim_, npc = width_;
  const std::size_t d = std::size_t(dim);
  const CellMaps maps(dim, nodes, cells, npc);
  const CellBuckets buckets(dim, nodes, cells, npc, maps);
  inside_.assign(n_points_, 0);
  ids_.assign(n_points_ * std::size_t(width_), 0);
  weights_.assign(n_points_ * std::size_t(width_), 0.0);
  std::vector<std::size_t> outside;  // points that take the closest-point extension
  const auto set_cell = [&](std::size_t p, std::size_t c, const double* l) {
    const std::int64_t* v = cells.data() + c * std::size_t(npc);
    std::int32_t* id = ids_.data() + p * std::size_t(width_);
    for (int k = 0; k < npc; ++k) id[k] = std::int32_t(v[k]);
    cell_basis(dim, degree_, l, weights_.data() + p * std::size_t(width_));
  };
  std::size_t last = 0;  // previous point's cell: neighbouring points often share it
  bool have_last = false;
  std::array<double, 4> l{}, best_l{};
  for (std::size_t p = 0; p < n_points_; ++p) {
    const double* x = points.data() + p * d;
    double best = -HUGE_VAL;
    std::size_t best_cell = 0;
    if (have_last) {
      best = maps.barycentric(last, x, l.data());
      best_cell = last;
      best_l = l;
    }
    if (best <= kInside) {
      for (const std::int32_t c : buckets.candidates(x)) {
        const double m = maps.barycentric(std::size_t(c), x, l.data());
        if (m > best) {
          best = m, best_cell = std::size_t(c), best_l = l;
          if (m > kInside) break;
        }
      }
    }
    if (best > kInside) {
      inside_[p] = 1;
      set_cell(p, best_cell, best_l.data());
      last = best_cell, have_last = true;
    } else if (best >= -kNear && distance.side({x, d}) <= 0) {
      // On a face (or within round-off of one), inside or on the boundary.
      inside_[p] = 1;
      if (best < -kInside) ++n_snapped_;
      clamp_barycentric(best_l.data(), dim + 1);
      set_cell(p, best_cell, best_l.data());
      last = best_cell, have_last = true;
    } else {
      outside.push_back(p);
    }
  }
  return outside;
}

void MeshSampler::extend_from_boundary(const std::vector<std::size_t>& outside, std::span<const std::int64_t> cells,
                                       const geometry::Boundary& boundary, const geometry::SignedDistance& distance,
                                       std::span<const double> points) {
  const int dim = dim_;
  const std::size_t d = std::size_t(dim);
  const std::vector<std::int32_t> fnodes = facet_nodes(dim, degree_, cells, width_, boundary);
  const int fw = degree_ == 1 ? dim : (dim == 2 ? 3 : 6);
  std::vector<double> xo(outside.size() * d);
  for (std::size_t i = 0; i < outside.size(); ++i) std::copy_n(points.data() + outside[i] * d, d, xo.data() + i * d);
  std::vector<geometry::ClosestPoint> hits(outside.size());
  distance.closest(xo, hits);
  // Scale for "at the boundary up to round-off" (bounding box of the boundary).
  double diag2 = 0;
  std::array<double, 3> lo{HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi{-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  for (std::size_t i = 0; i < boundary.points.size(); ++i) {
    lo[i % d] = std::min(lo[i % d], boundary.points[i]);
    hi[i % d] = std::max(hi[i % d], boundary.points[i]);
  }
  for (std::size_t k = 0; k < d; ++k) diag2 += (hi[k] - lo[k]) * (hi[k] - lo[k]);
  const double near_boundary = 1e-10 * std::sqrt(diag2);
  for (std::size_t i = 0; i < outside.size(); ++i) {
    const std::size_t p = outside[i];
    const geometry::ClosestPoint& h = hits[i];
    assert(h.facet >= 0);
    // Not in any cell, so outside unless round-off misled the location (see kNear).
    if (h.distance <= near_boundary && distance.side({points.data() + p * d, d}) <= 0) {
      inside_[p] = 1;
      ++n_snapped_;
    }
    double m[3];
    facet_barycentric(boundary, h.facet, h.point.data(), m);
    const std::int32_t* fn = fnodes.data() + std::size_t(h.facet) * std::size_t(fw);
    std::int32_t* id = ids_.data() + p * std::size_t(width_);
    double* w = weights_.data() + p * std::size_t(width_);
    for (int k = 0; k < width_; ++k) id[k] = fn[k < fw ? k : 0];  // padding: weight 0
    facet_basis(dim, degree_, m, w);
  }
}

void MeshSampler::interpolate(std::span<const double> field, int n_comp,
                              std::span<double> out) const {
  if (n_comp < 1) fail("interpolate: n_comp must be >= 1, got " + std::to_string(n_comp));
  const std::size_t nc = std::size_t(n_comp), w = std::size_t(width_);
  if (field.size() != n_nodes_ * nc)
    fail("interpolate: field has " + std::to_string(field.size()) + " values, expected " +
         std::to_string(n_nodes_) + " x " + std::to_string(n_comp));
  if (out.size() != n_points_ * nc)
    fail("interpolate: output has " + std::to_string(out.size()) + " values, expected " +
         std::to_string(n_points_) + " x " + std::to_string(n_comp));
  const auto gather = [&]<std::size_t N>(std::integral_constant<std::size_t, N>) {
    for (std::size_t p = 0; p < n_points_; ++p) {
      const std::int32_t* id = ids_.data() + p * w;
      const double* wt = weights_.data() + p * w;
      std::array<double, N> acc{};
      for (std::size_t k = 0; k < w; ++k) {
        const double* f = field.data() + std::size_t(id[k]) * N;
        for (std::size_t c = 0; c < N; ++c) acc[c] += wt[k] * f[c];
      }
      std::copy(acc.begin(), acc.end(), out.begin() + std::ptrdiff_t(p * N));
    }
  };
  switch (n_comp) {
    case 1:
      gather(std::integral_constant<std::size_t, 1>{});
      return;
    case 2:
      gather(std::integral_constant<std::size_t, 2>{});
      return;
    case 3:
      gather(std::integral_constant<std::size_t, 3>{});
      return;
    default:
      break;
  }
  for (std::size_t p = 0; p < n_points_; ++p) {
    const std::int32_t* id = ids_.data() + p * w;
    const double* wt = weights_.data() + p * w;
    double* o = out.data() + p * nc;
    std::fill_n(o, nc, 0.0);
    for (std::size_t k = 0; k < w; ++k) {
      const double* f = field.data() + std::size_t(id[k]) * nc;
      for (std::size_t c = 0; c < nc; ++c) o[c] += wt[k] * f[c];
    }
  }
}

std::vector<double> MeshSampler::interpolate(std::span<const double> field, int n_comp) const {
  std::vector<double> out(n_points_ * std::size_t(std::max(n_comp, 0)));
  interpolate(field, n_comp, out);
  return out;
}

}  // namespace hypershape::sampling
