// The only CGAL translation unit of geometry/ (CGAL TUs compile slowly): detail::FacetTree (the
// trees and exact predicates) and the public distance classes on top of it. metrics.cpp reaches
// the trees through aabb.hpp.
//
//  - distances: our own bounding-volume hierarchy (class Bvh below, with oriented boxes), 2-4x
//    faster than CGAL::AABB_tree on 64^3 grids; closest points on facets computed in doubles;
//  - 2D inside/outside: winding number with CGAL's exact orientation predicate (PolygonSide);
//  - 3D inside/outside: CGAL's ray-parity test (the one behind Side_of_triangle_mesh) on a
//    CGAL::AABB_tree of the same triangles, built only for SignedDistance.
#include "hypershape/geometry/distance.hpp"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
// The ray-parity point location behind CGAL::Side_of_triangle_mesh, used directly on our own
// triangle tree: Side_of_triangle_mesh itself wants a FaceGraph (Surface_mesh), i.e. a second,
// heavier tree type for the same triangles.
#include <CGAL/Polygon_mesh_processing/internal/Side_of_triangle_mesh/Point_inside_vertical_ray_cast.h>

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "aabb.hpp"

namespace hypershape::geometry {
namespace detail {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point_3 = K::Point_3;
using Point_2 = K::Point_2;
using Segment_3 = K::Segment_3;
using Triangle_3 = K::Triangle_3;

Point_3 to_point(const double* x, int dim) { return {x[0], x[1], dim == 3 ? x[2] : 0.0}; }

/// Exact point-in-polygon for a closed polygon (any number of loops): winding number with exact
/// orientation predicates over the segments registered in the horizontal slab of the query.
/// Slab indices are a monotone function of y (floor((y - y0) * inv_h) rounds monotonically), so a
/// segment is found in every slab whose y the segment spans: no exactness is lost to the index.
class PolygonSide {
 public:
  explicit PolygonSide(std::vector<std::array<Point_2, 2>> segments)
      : segments_(std::move(segments)) {
    double ymin = HUGE_VAL, ymax = -HUGE_VAL;
    for (const auto& s : segments_)
      for (const auto& p : s) ymin = std::min(ymin, p.y()), ymax = std::max(ymax, p.y());
    n_slabs_ = int(std::clamp<std::size_t>(segments_.size(), 1, 1 << 14));
    y0_ = ymin;
    inv_h_ = ymax > ymin ? n_slabs_ / (ymax - ymin) : 0.0;
    start_.assign(std::size_t(n_slabs_) + 1, 0);
    for (int pass = 0; pass < 2; ++pass) {
      std::vector<int> fill(start_.begin(), start_.end() - 1);
      for (std::size_t i = 0; i < segments_.size(); ++i) {
        const auto& [a, b] = segments_[i];
        const int lo = slab(std::min(a.y(), b.y())), hi = slab(std::max(a.y(), b.y()));
        for (int k = lo; k <= hi; ++k) {
          if (pass == 0)
            ++start_[std::size_t(k) + 1];
          else
            items_[std::size_t(fill[std::size_t(k)]++)] = int(i);
        }
      }
      if (pass == 0) {
        for (int k = 0; k < n_slabs_; ++k) start_[std::size_t(k) + 1] += start_[std::size_t(k)];
        items_.resize(std::size_t(start_.back()));
      }
    }
  }

  int side(const Point_2& p) const {
    const int k = slab(p.y());
    int winding = 0;
    for (int i = start_[std::size_t(k)]; i < start_[std::size_t(k) + 1]; ++i) {
      const auto& [a, b] = segments_[std::size_t(items_[std::size_t(i)])];
      // On the segment: in its bounding box and collinear (both exact).
      if (std::min(a.x(), b.x()) <= p.x() && p.x() <= std::max(a.x(), b.x()) &&
          std::min(a.y(), b.y()) <= p.y() && p.y() <= std::max(a.y(), b.y()) &&
          CGAL::orientation(a, b, p) == CGAL::COLLINEAR)
        return 0;
      // Sunday's winding number: upward crossings with p on the left count +1, downward
      // crossings with p on the right -1.
      if (a.y() <= p.y()) {
        if (b.y() > p.y() && CGAL::orientation(a, b, p) == CGAL::LEFT_TURN) ++winding;
      } else if (b.y() <= p.y() && CGAL::orientation(a, b, p) == CGAL::RIGHT_TURN) {
        --winding;
      }
    }
    return winding != 0 ? -1 : 1;
  }

 private:
  int slab(double y) const {
    const double s = std::floor((y - y0_) * inv_h_);
    return int(std::clamp(s, 0.0, double(n_slabs_ - 1)));
  }

  std::vector<std::array<Point_2, 2>> segments_;
  int n_slabs_ = 1;
  double y0_ = 0, inv_h_ = 0;
  std::vector<int> start_, items_;
};

/// Closest point of segment ab to p.
Point_3 closest_on(const Segment_3& s, const Point_3& p) {
  const Point_3& a = s.source();
  const Point_3& b = s.target();
  const double ab[3] = {b.x() - a.x(), b.y() - a.y(), b.z() - a.z()};
  const double ap[3] = {p.x() - a.x(), p.y() - a.y(), p.z() - a.z()};
  const double t = std::clamp((ab[0] * ap[0] + ab[1] * ap[1] + ab[2] * ap[2]) /
                                  (ab[0] * ab[0] + ab[1] * ab[1] + ab[2] * ab[2]),
                              0.0, 1.0);
  return {a.x() + t * ab[0], a.y() + t * ab[1], a.z() + t * ab[2]};
}

/// Closest point of triangle abc to p, by the Voronoi regions of its vertices, edges and face
/// (Ericson, Real-Time Collision Detection, 5.1.5). Written out because it is the inner loop of
/// every distance query and 4x faster than K::Construct_projected_point_3 (measured).
Point_3 closest_on(const Triangle_3& t, const Point_3& p) {
  using V = std::array<double, 3>;
  const auto sub = [](const Point_3& u, const Point_3& v) {
    return V{u.x() - v.x(), u.y() - v.y(), u.z() - v.z()};
  };
  const auto dot = [](const V& u, const V& v) { return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]; };
  const auto at = [](const Point_3& o, const V& u, double s, const V& v, double r) {
    return Point_3(o.x() + s * u[0] + r * v[0], o.y() + s * u[1] + r * v[1],
                   o.z() + s * u[2] + r * v[2]);
  };
  const Point_3& a = t.vertex(0);
  const Point_3& b = t.vertex(1);
  const Point_3& c = t.vertex(2);
  const V ab = sub(b, a), ac = sub(c, a), ap = sub(p, a);
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const V bp = sub(p, b);
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return at(a, ab, d1 / (d1 - d3), ac, 0.0);
  const V cp = sub(p, c);
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return at(a, ab, 0.0, ac, d2 / (d2 - d6));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return at(b, sub(c, b), w, ab, 0.0);
  }
  const double denom = 1 / (va + vb + vc);
  return at(a, ab, vb * denom, ac, vc * denom);
}

/// A bounding-volume hierarchy for closest-point queries on facets, with two bounds per node:
/// its axis-aligned box and an oriented box in the frame of the node's mean facet normal.
///
/// Why not CGAL::AABB_tree for this: its nodes only have axis-aligned boxes, whose lower bound
/// on the distance is loose by the box size. From a point at distance D of a curved surface with
/// facets of size h, every facet within D + O(h) must then be projected, O(D / h) of them: 150
/// per query on a 20k-triangle surface and a 64^3 grid (measured), 1.5 s per grid. An oriented
/// box of a patch is as thin as the patch's sagitta, which cuts that to a handful.
template <class Datum>
class Bvh {
  static constexpr int n_vertices = std::is_same_v<Datum, Segment_3> ? 2 : 3;
  static constexpr int leaf_size = 4;
  using Vec = std::array<double, 3>;

  struct Node {
    std::array<double, 6> box;  // min x, y, z, max x, y, z
    std::array<Vec, 3> axis;    // orthonormal frame of the oriented box
    Vec lo, hi;                 // extents along the axes
    std::int32_t left = -1;     // children (internal) or -1 (leaf)
    std::int32_t right = -1;
    std::int32_t first = 0;  // facets [first, first + count) (leaf)
    std::int32_t count = 0;
  };

 public:
  /// Reorders `data` (and `ids` with it) into leaf order.
  Bvh(std::vector<Datum>& data, std::vector<std::int64_t>& ids) {
    const std::size_t n = data.size();
    assert(n > 0 && n < std::size_t(INT32_MAX));
    std::vector<std::int32_t> order(n);
    std::vector<Vec> centroid(n);
    for (std::size_t i = 0; i < n; ++i) {
      order[i] = std::int32_t(i);
      Vec c{0, 0, 0};
      for (int k = 0; k < n_vertices; ++k)
        for (int j = 0; j < 3; ++j) c[std::size_t(j)] += data[i].vertex(k)[j] / n_vertices;
      centroid[i] = c;
    }
    nodes_.reserve(2 * n / leaf_size + 2);
    build(data, centroid, order, 0, std::int32_t(n));
    std::vector<Datum> sorted_data;
    std::vector<std::int64_t> sorted_ids;
    sorted_data.reserve(n);
    sorted_ids.reserve(n);
    for (const std::int32_t i : order) {
      sorted_data.push_back(data[std::size_t(i)]);
      sorted_ids.push_back(ids[std::size_t(i)]);
    }
    data = std::move(sorted_data);
    ids = std::move(sorted_ids);
  }

  const std::array<double, 6>& box() const { return nodes_.front().box; }

  /// Updates `best` (point, primitive, squared distance) with the closest point to q on the
  /// facets f with !skip(f), if closer than best.squared_distance.
  template <class Skip>
  void nearest(const std::vector<Datum>& data, const Point_3& q, ClosestHit& best,
               const Skip& skip) const {
    struct Entry {
      std::int32_t node;
      double lower;
    };
    std::array<Entry, 128> stack;  // depth <= log2(n / leaf_size) + 1 (median splits)
    int top = 0;
    stack[std::size_t(top++)] = {0, lower_bound(nodes_[0], q, best.squared_distance)};
    while (top > 0) {
      const Entry e = stack[std::size_t(--top)];
      if (e.lower >= best.squared_distance) continue;
      const Node& node = nodes_[std::size_t(e.node)];
      if (node.left < 0) {
        for (std::int32_t i = node.first; i < node.first + node.count; ++i) {
          if (skip(i)) continue;
          const Point_3 x = closest_on(data[std::size_t(i)], q);
          const double d2 = CGAL::squared_distance(q, x);
          if (d2 < best.squared_distance) {
            best.point = {x.x(), x.y(), x.z()};
            best.primitive = i;
            best.squared_distance = d2;
          }
        }
        continue;
      }
      assert(top + 2 <= int(stack.size()));
      const double l = lower_bound(nodes_[std::size_t(node.left)], q, best.squared_distance);
      const double r = lower_bound(nodes_[std::size_t(node.right)], q, best.squared_distance);
      // Nearer child on top of the stack, so that it is searched first.
      if (l < r) {
        if (r < best.squared_distance) stack[std::size_t(top++)] = {node.right, r};
        if (l < best.squared_distance) stack[std::size_t(top++)] = {node.left, l};
      } else {
        if (l < best.squared_distance) stack[std::size_t(top++)] = {node.left, l};
        if (r < best.squared_distance) stack[std::size_t(top++)] = {node.right, r};
      }
    }
  }

 private:
  /// max(squared distance to the box, squared distance to the oriented box); the second is only
  /// computed if the first does not already reach `cutoff`.
  static double lower_bound(const Node& n, const Point_3& q, double cutoff) {
    const Vec d{q.x(), q.y(), q.z()};
    double box2 = 0;
    for (std::size_t j = 0; j < 3; ++j) {
      const double e = std::max({n.box[j] - d[j], d[j] - n.box[j + 3], 0.0});
      box2 += e * e;
    }
    if (box2 >= cutoff) return box2;
    double obb2 = 0;
    for (std::size_t k = 0; k < 3; ++k) {
      const Vec& u = n.axis[k];
      const double t = u[0] * d[0] + u[1] * d[1] + u[2] * d[2];
      const double e = std::max({n.lo[k] - t, t - n.hi[k], 0.0});
      obb2 += e * e;
    }
    return std::max(box2, obb2);
  }

  std::int32_t build(const std::vector<Datum>& data, const std::vector<Vec>& centroid,
                     std::vector<std::int32_t>& order, std::int32_t first, std::int32_t last) {
    const auto index = std::int32_t(nodes_.size());
    nodes_.emplace_back();
    Node node = bound(data, order, first, last);
    if (last - first <= leaf_size) {
      node.first = first;
      node.count = last - first;
      nodes_[std::size_t(index)] = node;
      return index;
    }
    const std::int32_t mid = median_split(centroid, order, first, last);
    node.left = build(data, centroid, order, first, mid);
    node.right = build(data, centroid, order, mid, last);
    nodes_[std::size_t(index)] = node;
    return index;
  }

  /// A node's bounds over facets order[first, last): the axis-aligned box and the oriented box.
  Node bound(const std::vector<Datum>& data, const std::vector<std::int32_t>& order, std::int32_t first,
             std::int32_t last) const {
    Node node;
    // Axis-aligned box and area-weighted mean normal.
    node.box = {HUGE_VAL, HUGE_VAL, HUGE_VAL, -HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    Vec normal{0, 0, 0};
    double total = 0;
    for (std::int32_t i = first; i < last; ++i) {
      const Datum& f = data[std::size_t(order[std::size_t(i)])];
      for (int k = 0; k < n_vertices; ++k)
        for (int j = 0; j < 3; ++j) {
          node.box[std::size_t(j)] = std::min(node.box[std::size_t(j)], f.vertex(k)[j]);
          node.box[std::size_t(j) + 3] = std::max(node.box[std::size_t(j) + 3], f.vertex(k)[j]);
        }
      const Vec n = facet_normal(f);
      for (int j = 0; j < 3; ++j) normal[std::size_t(j)] += n[std::size_t(j)];
      total += std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    }
    node.axis = frame(normal, total);
    node.lo = {HUGE_VAL, HUGE_VAL, HUGE_VAL};
    node.hi = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    double scale = 0;
    for (std::int32_t i = first; i < last; ++i) {
      const Datum& f = data[std::size_t(order[std::size_t(i)])];
      for (int k = 0; k < n_vertices; ++k) {
        const Point_3& p = f.vertex(k);
        for (int j = 0; j < 3; ++j) {
          const Vec& u = node.axis[std::size_t(j)];
          const double t = u[0] * p.x() + u[1] * p.y() + u[2] * p.z();
          node.lo[std::size_t(j)] = std::min(node.lo[std::size_t(j)], t);
          node.hi[std::size_t(j)] = std::max(node.hi[std::size_t(j)], t);
          scale = std::max(scale, std::abs(t));
        }
      }
    }
    // The projections are rounded (the box is not): widen by far more than their error so that
    // the bound stays a bound.
    for (int j = 0; j < 3; ++j) {
      node.lo[std::size_t(j)] -= 1e-12 * scale;
      node.hi[std::size_t(j)] += 1e-12 * scale;
    }
    return node;
  }

  /// Oriented frame: the mean normal (sum `normal` of facet normals of total length `total`) if
  /// the facets agree on one, else the coordinate axes (the oriented box is then the
  /// axis-aligned one).
  static std::array<Vec, 3> frame(const Vec& normal, double total) {
    const double len =
        std::sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]);
    if (!(len > 0.5 * total && len > 0)) return {Vec{1, 0, 0}, Vec{0, 1, 0}, Vec{0, 0, 1}};
    const Vec w = {normal[0] / len, normal[1] / len, normal[2] / len};
    // Any unit vector orthogonal to w: cross with the coordinate axis least aligned with it.
    const int a = std::abs(w[0]) <= std::abs(w[1]) && std::abs(w[0]) <= std::abs(w[2]) ? 0
                  : std::abs(w[1]) <= std::abs(w[2])                                   ? 1
                                                                                       : 2;
    Vec e{0, 0, 0};
    e[std::size_t(a)] = 1;
    Vec u = cross(w, e);
    const double lu = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    u = {u[0] / lu, u[1] / lu, u[2] / lu};
    return {u, cross(w, u), w};
  }

  /// Median split of order[first, last) by the centroids along their longest extent; the index
  /// of the split.
  static std::int32_t median_split(const std::vector<Vec>& centroid, std::vector<std::int32_t>& order,
                                   std::int32_t first, std::int32_t last) {
    Vec cmin{HUGE_VAL, HUGE_VAL, HUGE_VAL}, cmax{-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    for (std::int32_t i = first; i < last; ++i)
      for (int j = 0; j < 3; ++j) {
        cmin[std::size_t(j)] = std::min(
            cmin[std::size_t(j)], centroid[std::size_t(order[std::size_t(i)])][std::size_t(j)]);
        cmax[std::size_t(j)] = std::max(
            cmax[std::size_t(j)], centroid[std::size_t(order[std::size_t(i)])][std::size_t(j)]);
      }
    int axis = 0;
    for (int j = 1; j < 3; ++j)
      if (cmax[std::size_t(j)] - cmin[std::size_t(j)] >
          cmax[std::size_t(axis)] - cmin[std::size_t(axis)])
        axis = j;
    const std::int32_t mid = first + (last - first) / 2;
    std::nth_element(order.begin() + first, order.begin() + mid, order.begin() + last,
                     [&](std::int32_t a, std::int32_t b) {
                       return centroid[std::size_t(a)][std::size_t(axis)] <
                              centroid[std::size_t(b)][std::size_t(axis)];
                     });
    return mid;
  }

  static Vec cross(const Vec& a, const Vec& b) {
    return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
  }
  /// Normal scaled by the measure (length / twice the area).
  static Vec facet_normal(const Datum& f) {
    const Point_3& a = f.vertex(0);
    const Point_3& b = f.vertex(1);
    if constexpr (n_vertices == 2) {
      return {b.y() - a.y(), a.x() - b.x(), 0.0};
    } else {
      const Point_3& c = f.vertex(2);
      return cross({b.x() - a.x(), b.y() - a.y(), b.z() - a.z()},
                   {c.x() - a.x(), c.y() - a.y(), c.z() - a.z()});
    }
  }

  std::vector<Node> nodes_;
};

using TriangleTree = CGAL::AABB_tree<CGAL::AABB_traits<
    K, CGAL::AABB_triangle_primitive<K, std::vector<Triangle_3>::const_iterator>>>;

}  // namespace

struct FacetTree::Impl {
  virtual ~Impl() = default;
  virtual double bbox_diagonal() const = 0;
  virtual ClosestHit closest(const double* x) const = 0;
  virtual ClosestHit closest(const double* x, const ClosestHit& hint) const = 0;
  virtual ClosestHit closest_if(const double* x, double bound_sq, FacetFilter skip) const = 0;
  virtual double squared_distance_to(const double* x, std::int64_t primitive) const = 0;
  virtual int side(const double* x) const = 0;
};

namespace {

template <class Datum>
class TreeImpl final : public FacetTree::Impl {
  static constexpr int dim = std::is_same_v<Datum, Segment_3> ? 2 : 3;

 public:
  TreeImpl(std::vector<Datum> data, std::vector<std::int64_t> facet_ids, bool with_side)
      : data_(std::move(data)), facet_ids_(std::move(facet_ids)), bvh_(data_, facet_ids_) {
    with_side_ = with_side;
    if (!with_side) return;
    if constexpr (dim == 2) {
      std::vector<std::array<Point_2, 2>> segments;
      segments.reserve(data_.size());
      for (const auto& s : data_) {
        const auto& a = s.vertex(0);
        const auto& b = s.vertex(1);
        segments.push_back({Point_2(a.x(), a.y()), Point_2(b.x(), b.y())});
      }
      polygon_side_ = std::make_unique<PolygonSide>(std::move(segments));
    } else {
      side_tree_ = std::make_unique<TriangleTree>(data_.cbegin(), data_.cend());
      side_tree_->build();
    }
  }

  double bbox_diagonal() const override {
    const auto& b = bvh_.box();
    double d2 = 0;
    for (std::size_t i = 0; i < 3; ++i) d2 += (b[i + 3] - b[i]) * (b[i + 3] - b[i]);
    return std::sqrt(d2);
  }

  ClosestHit closest(const double* x) const override {
    ClosestHit hit;
    bvh_.nearest(data_, to_point(x, dim), hit, [](std::int32_t) { return false; });
    hit.facet = facet_ids_[std::size_t(hit.primitive)];
    return hit;
  }

  ClosestHit closest(const double* x, const ClosestHit& hint) const override {
    assert(hint.primitive >= 0 && hint.primitive < std::int64_t(data_.size()));
    const Point_3 q = to_point(x, dim);
    // The closest point on the hint's facet bounds the answer from the start.
    ClosestHit hit;
    const Point_3 y = closest_on(data_[std::size_t(hint.primitive)], q);
    hit.point = {y.x(), y.y(), y.z()};
    hit.primitive = hint.primitive;
    hit.squared_distance = CGAL::squared_distance(q, y);
    bvh_.nearest(data_, q, hit, [](std::int32_t) { return false; });
    hit.facet = facet_ids_[std::size_t(hit.primitive)];
    return hit;
  }

  ClosestHit closest_if(const double* x, double bound_sq, FacetFilter skip) const override {
    ClosestHit hit;
    hit.squared_distance = bound_sq;
    bvh_.nearest(data_, to_point(x, dim), hit,
                 [&](std::int32_t i) { return skip(facet_ids_[std::size_t(i)]); });
    if (hit.primitive >= 0) hit.facet = facet_ids_[std::size_t(hit.primitive)];
    return hit;
  }

  double squared_distance_to(const double* x, std::int64_t primitive) const override {
    assert(primitive >= 0 && primitive < std::int64_t(data_.size()));
    const Point_3 q = to_point(x, dim);
    return CGAL::squared_distance(q, closest_on(data_[std::size_t(primitive)], q));
  }

  int side(const double* x) const override {
    assert(with_side_);
    if constexpr (dim == 2) {
      return polygon_side_->side(Point_2(x[0], x[1]));
    } else {
      const Point_3 q = to_point(x, 3);
      const auto& b = bvh_.box();
      for (std::size_t i = 0; i < 3; ++i)
        if (q[int(i)] < b[i] || q[int(i)] > b[i + 3]) return 1;
      switch (CGAL::internal::Point_inside_vertical_ray_cast<K, TriangleTree>()(q, *side_tree_)) {
        case CGAL::ON_BOUNDED_SIDE:
          return -1;
        case CGAL::ON_BOUNDARY:
          return 0;
        default:
          return 1;
      }
    }
  }

 private:
  std::vector<Datum> data_;              // facets in leaf order of bvh_
  std::vector<std::int64_t> facet_ids_;  // facet index in the Boundary of data_[i]
  Bvh<Datum> bvh_;
  bool with_side_ = false;
  std::unique_ptr<PolygonSide> polygon_side_;  // 2D
  std::unique_ptr<TriangleTree> side_tree_;    // 3D: CGAL's tree for its ray-parity test
};

}  // namespace

FacetTree::FacetTree(const Boundary& boundary, std::span<const std::int64_t> facets, bool with_side)
    : dim_(boundary.dim) {
  if (dim_ != 2 && dim_ != 3)
    throw std::invalid_argument("geometry: boundary dimension must be 2 or 3, got " +
                                std::to_string(dim_));
  const std::int64_t n_facets = boundary.n_facets(), n_points = boundary.n_points();
  if (boundary.points.size() != std::size_t(n_points * dim_) ||
      boundary.facets.size() != std::size_t(n_facets * dim_))
    throw std::invalid_argument("geometry: boundary arrays are not multiples of its dimension");
  for (const int v : boundary.facets)
    if (v < 0 || v >= n_points)
      throw std::invalid_argument("geometry: facet refers to point " + std::to_string(v) + " of " +
                                  std::to_string(n_points));
  std::vector<std::int64_t> ids;
  if (facets.empty()) {
    ids.resize(std::size_t(n_facets));
    for (std::int64_t f = 0; f < n_facets; ++f) ids[std::size_t(f)] = f;
  } else {
    ids.assign(facets.begin(), facets.end());
    for (const std::int64_t f : ids)
      if (f < 0 || f >= n_facets)
        throw std::invalid_argument("geometry: facet index " + std::to_string(f) +
                                    " out of range [0, " + std::to_string(n_facets) + ")");
  }
  // Degenerate facets (a point, or collinear triangle vertices) are dropped: in a closed
  // boundary they are covered by their neighbours' edges, so neither the distance nor the
  // ray parity changes, and CGAL's projections onto them are ill-defined.
  std::vector<std::int64_t> kept;
  kept.reserve(ids.size());
  if (dim_ == 2) {
    std::vector<Segment_3> data;
    for (const std::int64_t f : ids) {
      const auto v = boundary.facet(f);
      const Point_3 a = to_point(boundary.point(v[0]).data(), 2);
      const Point_3 b = to_point(boundary.point(v[1]).data(), 2);
      if (a == b) continue;
      data.emplace_back(a, b);
      kept.push_back(f);
    }
    if (data.empty()) throw std::invalid_argument("geometry: no (non-degenerate) facets");
    impl_ = std::make_unique<TreeImpl<Segment_3>>(std::move(data), std::move(kept), with_side);
  } else {
    std::vector<Triangle_3> data;
    for (const std::int64_t f : ids) {
      const auto v = boundary.facet(f);
      const Point_3 a = to_point(boundary.point(v[0]).data(), 3);
      const Point_3 b = to_point(boundary.point(v[1]).data(), 3);
      const Point_3 c = to_point(boundary.point(v[2]).data(), 3);
      if (CGAL::collinear(a, b, c)) continue;
      data.emplace_back(a, b, c);
      kept.push_back(f);
    }
    if (data.empty()) throw std::invalid_argument("geometry: no (non-degenerate) facets");
    impl_ = std::make_unique<TreeImpl<Triangle_3>>(std::move(data), std::move(kept), with_side);
  }
}

FacetTree::~FacetTree() = default;
FacetTree::FacetTree(FacetTree&&) noexcept = default;
FacetTree& FacetTree::operator=(FacetTree&&) noexcept = default;

double FacetTree::bbox_diagonal() const { return impl_->bbox_diagonal(); }
ClosestHit FacetTree::closest(const double* x) const { return impl_->closest(x); }
ClosestHit FacetTree::closest(const double* x, const ClosestHit& hint) const {
  return impl_->closest(x, hint);
}
ClosestHit FacetTree::closest_if(const double* x, double bound_sq, FacetFilter skip) const {
  return impl_->closest_if(x, bound_sq, skip);
}
double FacetTree::squared_distance_to(const double* x, std::int64_t primitive) const {
  return impl_->squared_distance_to(x, primitive);
}
int FacetTree::side(const double* x) const { return impl_->side(x); }

}  // namespace detail

// ---- SignedDistance ---------------------------------------------------------------------------

SignedDistance::SignedDistance(const Boundary& boundary)
    : tree_(std::make_unique<detail::FacetTree>(boundary, std::span<const std::int64_t>{}, true)) {}
SignedDistance::~SignedDistance() = default;
SignedDistance::SignedDistance(SignedDistance&&) noexcept = default;
SignedDistance& SignedDistance::operator=(SignedDistance&&) noexcept = default;

int SignedDistance::dim() const { return tree_->dim(); }

double SignedDistance::operator()(std::span<const double> x) const {
  assert(x.size() == std::size_t(dim()));
  const int side = tree_->side(x.data());
  if (side == 0) return 0.0;
  const double d = std::sqrt(tree_->closest(x.data()).squared_distance);
  return side < 0 ? -d : d;
}

void SignedDistance::evaluate(std::span<const double> points, std::span<double> out) const {
  const std::size_t d = std::size_t(dim());
  assert(points.size() == out.size() * d);
  detail::ClosestHit hit;
  for (std::size_t i = 0; i < out.size(); ++i) {
    const double* x = points.data() + i * d;
    const int side = tree_->side(x);
    if (side == 0) {
      out[i] = 0.0;
      continue;
    }
    hit = hit.facet < 0 ? tree_->closest(x) : tree_->closest(x, hit);
    const double dist = std::sqrt(hit.squared_distance);
    out[i] = side < 0 ? -dist : dist;
  }
}

int SignedDistance::side(std::span<const double> x) const {
  assert(x.size() == std::size_t(dim()));
  return tree_->side(x.data());
}

namespace {
ClosestPoint to_closest_point(const detail::ClosestHit& hit) {
  return {std::sqrt(hit.squared_distance), hit.facet, hit.point};
}
}  // namespace

ClosestPoint SignedDistance::closest(std::span<const double> x) const {
  assert(x.size() == std::size_t(dim()));
  return to_closest_point(tree_->closest(x.data()));
}

void SignedDistance::closest(std::span<const double> points, std::span<ClosestPoint> out) const {
  const std::size_t d = std::size_t(dim());
  assert(points.size() == out.size() * d);
  detail::ClosestHit hit;
  for (std::size_t i = 0; i < out.size(); ++i) {
    const double* x = points.data() + i * d;
    hit = hit.facet < 0 ? tree_->closest(x) : tree_->closest(x, hit);
    out[i] = to_closest_point(hit);
  }
}

// ---- FacetSetDistance -------------------------------------------------------------------------

FacetSetDistance::FacetSetDistance(const Boundary& boundary, std::span<const std::int64_t> facets) {
  if (facets.empty()) throw std::invalid_argument("FacetSetDistance: empty facet subset");
  tree_ = std::make_unique<detail::FacetTree>(boundary, facets, false);
}
FacetSetDistance::~FacetSetDistance() = default;
FacetSetDistance::FacetSetDistance(FacetSetDistance&&) noexcept = default;
FacetSetDistance& FacetSetDistance::operator=(FacetSetDistance&&) noexcept = default;

int FacetSetDistance::dim() const { return tree_->dim(); }

double FacetSetDistance::operator()(std::span<const double> x) const {
  assert(x.size() == std::size_t(dim()));
  return std::sqrt(tree_->closest(x.data()).squared_distance);
}

void FacetSetDistance::evaluate(std::span<const double> points, std::span<double> out) const {
  const std::size_t d = std::size_t(dim());
  assert(points.size() == out.size() * d);
  detail::ClosestHit hit;
  for (std::size_t i = 0; i < out.size(); ++i) {
    const double* x = points.data() + i * d;
    hit = hit.facet < 0 ? tree_->closest(x) : tree_->closest(x, hit);
    out[i] = std::sqrt(hit.squared_distance);
  }
}

}  // namespace hypershape::geometry
