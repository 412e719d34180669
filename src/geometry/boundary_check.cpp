#include "hypershape/geometry/boundary_check.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/box_intersection_d.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace hypershape::geometry {

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;

BoundaryCheck fail(std::string reason) { return {false, std::move(reason)}; }

/// Common structural checks: sizes, index range, finite coordinates.
std::optional<BoundaryCheck> check_arrays(const Boundary& b, const char* what_facet,
                                          std::int64_t min_facets) {
  const int d = b.dim;
  if (b.points.size() % std::size_t(d) != 0 || b.facets.size() % std::size_t(d) != 0)
    return fail(
        fmt::format("malformed boundary: {} coordinates and {} facet indices are not "
                    "multiples of the dimension {}",
                    b.points.size(), b.facets.size(), d));
  const std::int64_t n = b.n_points(), m = b.n_facets();
  if (m < min_facets)
    return fail(fmt::format("too few {}s: {} (a closed {} needs at least {})", what_facet, m,
                            d == 2 ? "polygon" : "surface", min_facets));
  for (std::int64_t f = 0; f < m; ++f)
    for (int k = 0; k < d; ++k) {
      const int v = b.facets[std::size_t(f * d + k)];
      if (v < 0 || v >= n)
        return fail(fmt::format("{} {} refers to point {}, which does not exist ({} points)",
                                what_facet, f, v, n));
    }
  for (std::int64_t i = 0; i < n; ++i)
    for (int k = 0; k < d; ++k)
      if (!std::isfinite(b.points[std::size_t(i * d + k)]))
        return fail(fmt::format("point {} has a non-finite coordinate", i));
  return std::nullopt;
}

std::string xy(const K::Point_2& p) { return fmt::format("({:.6g}, {:.6g})", p.x(), p.y()); }
std::string xyz(const K::Point_3& p) {
  return fmt::format("({:.6g}, {:.6g}, {:.6g})", p.x(), p.y(), p.z());
}

// ---- 2D ---------------------------------------------------------------------------------------

BoundaryCheck check_polygon(const Boundary& b) {
  if (auto r = check_arrays(b, "segment", 3)) return *r;
  const std::int64_t n = b.n_points(), m = b.n_facets();
  std::vector<K::Point_2> p(static_cast<std::size_t>(n));
  for (std::int64_t i = 0; i < n; ++i) p[i] = {b.points[2 * i], b.points[2 * i + 1]};
  auto seg = [&](std::int64_t f) { return b.facet(f); };

  for (std::int64_t f = 0; f < m; ++f) {
    const int a = seg(f)[0], c = seg(f)[1];
    if (a == c)
      return fail(fmt::format("zero-length segment {}: it starts and ends at point {}", f, a));
    if (p[a] == p[c])
      return fail(
          fmt::format("zero-length segment {}: points {} and {} coincide at {} "
                      "(repeated point)",
                      f, a, c, xy(p[a])));
  }

  // Every point starts one segment and ends one: then `next` is a permutation.
  std::vector<int> n_out(std::size_t(n), 0), n_in(std::size_t(n), 0);
  std::vector<std::int64_t> out_seg(std::size_t(n), -1);
  for (std::int64_t f = 0; f < m; ++f) {
    ++n_out[seg(f)[0]];
    ++n_in[seg(f)[1]];
    out_seg[seg(f)[0]] = f;
  }
  for (std::int64_t v = 0; v < n; ++v) {
    const int used = n_out[v] + n_in[v];
    if (used == 0) return fail(fmt::format("point {} is used by no segment", v));
    if (used != 2)
      return fail(fmt::format("point {} is used by {} segments (exactly 2 allowed)", v, used));
    if (n_out[v] != 1)
      return fail(
          fmt::format("inconsistent direction at point {}: it starts {} segments and ends "
                      "{} (the segments must run head to tail around one cycle)",
                      v, n_out[v], n_in[v]));
  }
  {
    std::int64_t steps = 0;
    const int start = seg(0)[0];
    int v = start;
    do {
      v = seg(out_seg[v])[1];
      ++steps;
    } while (v != start && steps <= m);
    if (steps != m)
      return fail(
          fmt::format("the segments form more than one closed loop: the loop through "
                      "segment 0 has {} of the {} segments (one loop allowed)",
                      steps, m));
  }

  // Intersections: a sweep over the bounding boxes (closed boxes, so touching counts), then exact
  // predicates on each candidate pair. Keep the smallest offending pair for a stable message.
  using Box =
      CGAL::Box_intersection_d::Box_with_info_d<double, 2, std::int64_t,
                                                CGAL::Box_intersection_d::ID_FROM_BOX_ADDRESS>;
  std::vector<Box> boxes;
  boxes.reserve(std::size_t(m));
  for (std::int64_t f = 0; f < m; ++f)
    boxes.emplace_back(p[seg(f)[0]].bbox() + p[seg(f)[1]].bbox(), f);
  std::vector<const Box*> ptrs(boxes.size());
  for (std::size_t i = 0; i < boxes.size(); ++i) ptrs[i] = &boxes[i];

  enum class Kind { none, fold, touch, cross };
  Kind kind = Kind::none;
  std::pair<std::int64_t, std::int64_t> worst{m, m};
  int touch_point = -1;
  auto record = [&](std::int64_t f, std::int64_t g, Kind k, int point) {
    if (f > g) std::swap(f, g);
    if (std::make_pair(f, g) < worst) {
      worst = {f, g};
      kind = k;
      touch_point = point;
    }
  };
  auto callback = [&](const Box* bf, const Box* bg) {
    const std::int64_t f = bf->info(), g = bg->info();
    const int f0 = seg(f)[0], f1 = seg(f)[1], g0 = seg(g)[0], g1 = seg(g)[1];
    if (f1 == g0 || g1 == f0) {  // consecutive: they may only share their common point
      const int s = f1 == g0 ? f1 : f0;
      const int a = f1 == g0 ? f0 : g0;  // the other end of the segment before s
      const int c = f1 == g0 ? g1 : f1;  // the other end of the segment after s
      if (f1 == g0 && g1 == f0) return;  // only for 2-gons, excluded above
      if (CGAL::collinear(p[a], p[s], p[c]) &&
          !CGAL::collinear_are_strictly_ordered_along_line(p[a], p[s], p[c]))
        record(f, g, Kind::fold, s);
      return;
    }
    const K::Segment_2 sf(p[f0], p[f1]), sg(p[g0], p[g1]);
    if (!CGAL::do_intersect(sf, sg)) return;
    int on = -1;
    if (sg.has_on(p[f0]))
      on = f0;
    else if (sg.has_on(p[f1]))
      on = f1;
    else if (sf.has_on(p[g0]))
      on = g0;
    else if (sf.has_on(p[g1]))
      on = g1;
    record(f, g, on >= 0 ? Kind::touch : Kind::cross, on);
  };
  CGAL::box_self_intersection_d<CGAL::Sequential_tag>(ptrs.begin(), ptrs.end(), callback);
  if (kind != Kind::none) {
    const auto [f, g] = worst;
    if (kind == Kind::fold)
      return fail(
          fmt::format("self-overlapping polygon: consecutive segments {} and {} fold back "
                      "onto each other at point {} {}",
                      f, g, touch_point, xy(p[touch_point])));
    if (kind == Kind::touch)
      return fail(
          fmt::format("self-intersecting polygon: segments {} and {} touch at point {} "
                      "{}",
                      f, g, touch_point, xy(p[touch_point])));
    const K::Segment_2 sf(p[seg(f)[0]], p[seg(f)[1]]), sg(p[seg(g)[0]], p[seg(g)[1]]);
    std::string where;
    if (auto x = CGAL::intersection(sf, sg))
      if (const auto* q = boost::get<K::Point_2>(&*x)) where = " near " + xy(*q);
    return fail(
        fmt::format("self-intersecting polygon: segments {} and {} intersect{}", f, g, where));
  }

  double area2 = 0;
  for (std::int64_t f = 0; f < m; ++f) {
    const auto& a = p[seg(f)[0]];
    const auto& c = p[seg(f)[1]];
    area2 += a.x() * c.y() - a.y() * c.x();
  }
  if (!(area2 > 0))
    return fail(
        fmt::format("clockwise polygon: signed area {:.6g} (counter-clockwise, i.e. "
                    "positive area, required)",
                    0.5 * area2));
  return {true, {}};
}

// ---- 3D ---------------------------------------------------------------------------------------

struct UnionFind {
  std::vector<int> parent;
  explicit UnionFind(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(int a, int b) {
    a = find(a);
    b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

BoundaryCheck check_surface(const Boundary& b) {
  if (auto r = check_arrays(b, "triangle", 4)) return *r;
  const std::int64_t n = b.n_points(), m = b.n_facets();
  std::vector<K::Point_3> p(static_cast<std::size_t>(n));
  for (std::int64_t i = 0; i < n; ++i)
    p[i] = {b.points[3 * i], b.points[3 * i + 1], b.points[3 * i + 2]};
  const int* F = b.facets.data();

  {
    std::vector<char> used(std::size_t(n), 0);
    for (int v : b.facets) used[v] = 1;
    for (std::int64_t v = 0; v < n; ++v)
      if (!used[v]) return fail(fmt::format("point {} is used by no triangle", v));
  }
  for (std::int64_t f = 0; f < m; ++f) {
    const int a = F[3 * f], c = F[3 * f + 1], d = F[3 * f + 2];
    if (a == c || c == d || d == a)
      return fail(
          fmt::format("degenerate triangle {}: it repeats point {}", f, a == c || a == d ? a : c));
    if (CGAL::collinear(p[a], p[c], p[d]))
      return fail(
          fmt::format("degenerate triangle {}: zero area (points {}, {}, {} are "
                      "collinear)",
                      f, a, c, d));
  }

  // Edges: sort the 3m half-edges by their undirected key.
  struct HalfEdge {
    std::uint64_t key;
    std::int64_t facet;
    int from, to;
  };
  std::vector<HalfEdge> he(std::size_t(3 * m));
  for (std::int64_t f = 0; f < m; ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = F[3 * f + k], c = F[3 * f + (k + 1) % 3];
      const auto lo = std::uint64_t(std::min(a, c)), hi = std::uint64_t(std::max(a, c));
      he[std::size_t(3 * f + k)] = {(lo << 32) | hi, f, a, c};
    }
  std::sort(he.begin(), he.end(), [](const HalfEdge& x, const HalfEdge& y) {
    return x.key != y.key ? x.key < y.key : x.facet < y.facet;
  });
  std::int64_t n_open = 0;
  const HalfEdge* first_open = nullptr;
  const HalfEdge* first_nonmanifold = nullptr;
  std::size_t nonmanifold_count = 0, nonmanifold_at = 0;
  const HalfEdge* first_flip = nullptr;
  const HalfEdge* flip_other = nullptr;
  for (std::size_t i = 0; i < he.size();) {
    std::size_t j = i;
    while (j < he.size() && he[j].key == he[i].key) ++j;
    const std::size_t count = j - i;
    if (count == 1) {
      ++n_open;
      if (!first_open || he[i].facet < first_open->facet) first_open = &he[i];
    } else if (count > 2) {
      if (!first_nonmanifold || he[i].facet < first_nonmanifold->facet) {
        first_nonmanifold = &he[i];
        nonmanifold_count = count;
        nonmanifold_at = i;
      }
    } else if (he[i].from == he[i + 1].from) {
      if (!first_flip || he[i].facet < first_flip->facet) {
        first_flip = &he[i];
        flip_other = &he[i + 1];
      }
    }
    i = j;
  }
  if (n_open > 0)
    return fail(fmt::format(
        "open surface: {} boundary edge{} (first at points {}-{} of triangle "
        "{}); a closed surface has none",
        n_open, n_open == 1 ? "" : "s", first_open->from, first_open->to, first_open->facet));
  if (first_nonmanifold) {
    std::string list;
    for (std::size_t k = 0; k < nonmanifold_count; ++k)
      list += (k ? ", " : "") + std::to_string(he[nonmanifold_at + k].facet);
    return fail(fmt::format(
        "non-manifold edge: points {} and {} are shared by {} triangles ({}); "
        "exactly 2 allowed",
        std::min(first_nonmanifold->from, first_nonmanifold->to),
        std::max(first_nonmanifold->from, first_nonmanifold->to), nonmanifold_count, list));
  }
  if (first_flip)
    return fail(
        fmt::format("inconsistent orientation: triangles {} and {} both run along edge "
                    "{}->{} (each edge must be traversed once in each direction)",
                    first_flip->facet, flip_other->facet, first_flip->from, first_flip->to));

  // Vertex-manifold: the link of every point (edges b->c of its triangles (v, b, c)) is one cycle.
  {
    std::vector<std::int64_t> start(std::size_t(n) + 1, 0);
    for (int v : b.facets) ++start[std::size_t(v) + 1];
    for (std::int64_t v = 0; v < n; ++v) start[v + 1] += start[v];
    std::vector<std::pair<int, int>> link(b.facets.size());
    std::vector<std::int64_t> fill(start.begin(), start.end() - 1);
    for (std::int64_t f = 0; f < m; ++f)
      for (int k = 0; k < 3; ++k)
        link[std::size_t(fill[F[3 * f + k]]++)] = {F[3 * f + (k + 1) % 3], F[3 * f + (k + 2) % 3]};
    for (std::int64_t v = 0; v < n; ++v) {
      auto* lb = link.data() + start[v];
      auto* le = link.data() + start[v + 1];
      std::sort(lb, le);
      const std::int64_t k = le - lb;
      std::int64_t steps = 0;
      int w = lb->first;
      do {  // follow the link cycle through the first triangle
        auto it = std::lower_bound(lb, le, std::make_pair(w, std::numeric_limits<int>::min()));
        if (it == le || it->first != w) break;  // cannot happen for a closed oriented surface
        w = it->second;
        ++steps;
      } while (w != lb->first && steps <= k);
      if (steps != k) {
        // Count the fans for the message.
        std::vector<char> seen(std::size_t(k), 0);
        int n_fans = 0;
        for (std::int64_t s = 0; s < k; ++s) {
          if (seen[s]) continue;
          ++n_fans;
          int u = lb[s].first;
          for (std::int64_t guard = 0; guard <= k; ++guard) {
            auto it = std::lower_bound(lb, le, std::make_pair(u, std::numeric_limits<int>::min()));
            if (it == le || it->first != u || seen[it - lb]) break;
            seen[it - lb] = 1;
            u = it->second;
          }
        }
        return fail(
            fmt::format("non-manifold vertex: the {} triangles around point {} {} form {} "
                        "separate fans (one allowed)",
                        k, v, xyz(p[v]), n_fans));
      }
    }
  }

  {
    UnionFind uf{std::size_t(n)};
    for (std::int64_t f = 0; f < m; ++f) {
      uf.unite(F[3 * f], F[3 * f + 1]);
      uf.unite(F[3 * f], F[3 * f + 2]);
    }
    std::vector<std::int64_t> size(std::size_t(n), 0);
    for (std::int64_t f = 0; f < m; ++f) ++size[uf.find(F[3 * f])];
    std::vector<std::int64_t> sizes;
    for (auto s : size)
      if (s > 0) sizes.push_back(s);
    if (sizes.size() > 1) {
      std::sort(sizes.rbegin(), sizes.rend());
      std::string list;
      for (std::size_t k = 0; k < std::min<std::size_t>(sizes.size(), 5); ++k)
        list += (k ? ", " : "") + std::to_string(sizes[k]);
      if (sizes.size() > 5) list += ", ...";
      return fail(
          fmt::format("{} connected components ({} triangles); one closed surface "
                      "allowed",
                      sizes.size(), list));
    }
  }

  double vol6 = 0;
  for (std::int64_t f = 0; f < m; ++f) {
    const auto& a = p[F[3 * f]];
    const auto& c = p[F[3 * f + 1]];
    const auto& d = p[F[3 * f + 2]];
    vol6 += a.x() * (c.y() * d.z() - c.z() * d.y()) - a.y() * (c.x() * d.z() - c.z() * d.x()) +
            a.z() * (c.x() * d.y() - c.y() * d.x());
  }
  if (!(vol6 > 0))
    return fail(
        fmt::format("inward orientation: the enclosed volume is {:.6g} (outward normals, "
                    "i.e. positive volume, required)",
                    vol6 / 6));

  // Self-intersections (exact predicates), on a halfedge structure.
  using Mesh = CGAL::Surface_mesh<K::Point_3>;
  Mesh mesh;
  mesh.reserve(Mesh::size_type(n), Mesh::size_type(3 * m / 2), Mesh::size_type(m));
  for (const auto& q : p) mesh.add_vertex(q);
  for (std::int64_t f = 0; f < m; ++f) {
    const auto fd = mesh.add_face(Mesh::Vertex_index(F[3 * f]), Mesh::Vertex_index(F[3 * f + 1]),
                                  Mesh::Vertex_index(F[3 * f + 2]));
    if (fd == Mesh::null_face())  // not expected after the checks above
      return fail(fmt::format("non-manifold surface at triangle {}", f));
  }
  std::vector<std::pair<Mesh::Face_index, Mesh::Face_index>> pairs;
  CGAL::Polygon_mesh_processing::self_intersections(faces(mesh), mesh, std::back_inserter(pairs),
                                                    CGAL::parameters::maximum_number(1));
  if (!pairs.empty()) {
    auto [f, g] = pairs.front();
    std::int64_t i = f.idx(), j = g.idx();
    if (i > j) std::swap(i, j);
    return fail(fmt::format("self-intersecting surface: triangles {} and {} intersect", i, j));
  }
  return {true, {}};
}

}  // namespace

BoundaryCheck check_boundary(const Boundary& b) {
  if (b.dim == 2) return check_polygon(b);
  if (b.dim == 3) return check_surface(b);
  return fail(fmt::format("boundary of dimension {} (2 or 3 allowed)", b.dim));
}

}  // namespace hypershape::geometry
