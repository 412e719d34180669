#include "hypershape/geometry/boundary_check.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/box_intersection_d.h>
#include <fmt/format.h>

#include <algorithm>
#include <array>
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

/// A closed polygon as the 2D checks see it.
struct Polygon {
  const Boundary& b;
  std::int64_t n, m;          // points, segments
  std::vector<K::Point_2> p;  // the points
  std::array<int, 2> seg(std::int64_t f) const { return {b.facets[std::size_t(2 * f)], b.facets[std::size_t(2 * f + 1)]}; }
};

std::optional<BoundaryCheck> check_segments(const Polygon& P) {
  for (std::int64_t f = 0; f < P.m; ++f) {
    const int a = P.seg(f)[0], c = P.seg(f)[1];
    if (a == c) return fail(fmt::format("zero-length segment {}: it starts and ends at point {}", f, a));
    if (P.p[a] == P.p[c])
      return fail(fmt::format("zero-length segment {}: points {} and {} coincide at {} (repeated point)", f, a, c,
                              xy(P.p[a])));
  }
  return std::nullopt;
}

/// Every point starts one segment and ends one (then `next` is a permutation), and the
/// segments form one cycle.
std::optional<BoundaryCheck> check_one_cycle(const Polygon& P) {
  std::vector<int> n_out(std::size_t(P.n), 0), n_in(std::size_t(P.n), 0);
  std::vector<std::int64_t> out_seg(std::size_t(P.n), -1);
  for (std::int64_t f = 0; f < P.m; ++f) {
    ++n_out[P.seg(f)[0]];
    ++n_in[P.seg(f)[1]];
    out_seg[P.seg(f)[0]] = f;
  }
  for (std::int64_t v = 0; v < P.n; ++v) {
    const int used = n_out[v] + n_in[v];
    if (used == 0) return fail(fmt::format("point {} is used by no segment", v));
    if (used != 2) return fail(fmt::format("point {} is used by {} segments (exactly 2 allowed)", v, used));
    if (n_out[v] != 1)
      return fail(fmt::format(
          "inconsistent direction at point {}: it starts {} segments and ends {} (the segments must run head to "
          "tail around one cycle)",
          v, n_out[v], n_in[v]));
  }
  std::int64_t steps = 0;
  const int start = P.seg(0)[0];
  int v = start;
  do {
    v = P.seg(out_seg[v])[1];
    ++steps;
  } while (v != start && steps <= P.m);
  if (steps == P.m) return std::nullopt;
  return fail(fmt::format(
      "the segments form more than one closed loop: the loop through segment 0 has {} of the {} segments (one loop "
      "allowed)",
      steps, P.m));
}

/// The smallest pair of segments (f, g) that fold, touch or cross, and how.
struct Crossing {
  enum class Kind { none, fold, touch, cross } kind = Kind::none;
  std::pair<std::int64_t, std::int64_t> pair;
  int point = -1;
  void record(std::int64_t f, std::int64_t g, Kind k, int at) {
    if (f > g) std::swap(f, g);
    if (kind != Kind::none && std::make_pair(f, g) >= pair) return;
    pair = {f, g};
    kind = k;
    point = at;
  }
};

/// Classifies a candidate pair of segments whose boxes meet (exact predicates).
void classify_pair(const Polygon& P, std::int64_t f, std::int64_t g, Crossing& out) {
  using Kind = Crossing::Kind;
  const auto& p = P.p;
  const int f0 = P.seg(f)[0], f1 = P.seg(f)[1], g0 = P.seg(g)[0], g1 = P.seg(g)[1];
  if (f1 == g0 || g1 == f0) {  // consecutive: they may only share their common point
    const int s = f1 == g0 ? f1 : f0;
    const int a = f1 == g0 ? f0 : g0;  // the other end of the segment before s
    const int c = f1 == g0 ? g1 : f1;  // the other end of the segment after s
    if (f1 == g0 && g1 == f0) return;  // only for 2-gons, excluded above
    if (CGAL::collinear(p[a], p[s], p[c]) && !CGAL::collinear_are_strictly_ordered_along_line(p[a], p[s], p[c]))
      out.record(f, g, Kind::fold, s);
    return;
  }
  const K::Segment_2 sf(p[f0], p[f1]), sg(p[g0], p[g1]);
  if (!CGAL::do_intersect(sf, sg)) return;
  int on = -1;
  for (const auto& [seg, q] : {std::pair{&sg, f0}, {&sg, f1}, {&sf, g0}, {&sf, g1}})
    if (on < 0 && seg->has_on(p[q])) on = q;
  out.record(f, g, on >= 0 ? Kind::touch : Kind::cross, on);
}

/// Intersections: a sweep over the bounding boxes (closed boxes, so touching counts), then exact
/// predicates on each candidate pair. The smallest offending pair is named (a stable message).
std::optional<BoundaryCheck> check_polygon_intersections(const Polygon& P) {
  using Box = CGAL::Box_intersection_d::Box_with_info_d<double, 2, std::int64_t,
                                                        CGAL::Box_intersection_d::ID_FROM_BOX_ADDRESS>;
  std::vector<Box> boxes;
  boxes.reserve(std::size_t(P.m));
  for (std::int64_t f = 0; f < P.m; ++f) boxes.emplace_back(P.p[P.seg(f)[0]].bbox() + P.p[P.seg(f)[1]].bbox(), f);
  std::vector<const Box*> ptrs(boxes.size());
  for (std::size_t i = 0; i < boxes.size(); ++i) ptrs[i] = &boxes[i];
  Crossing c;
  CGAL::box_self_intersection_d<CGAL::Sequential_tag>(
      ptrs.begin(), ptrs.end(), [&](const Box* bf, const Box* bg) { classify_pair(P, bf->info(), bg->info(), c); });
  const auto [f, g] = c.pair;
  switch (c.kind) {
    case Crossing::Kind::none: return std::nullopt;
    case Crossing::Kind::fold:
      return fail(fmt::format(
          "self-overlapping polygon: consecutive segments {} and {} fold back onto each other at point {} {}", f, g,
          c.point, xy(P.p[c.point])));
    case Crossing::Kind::touch:
      return fail(fmt::format("self-intersecting polygon: segments {} and {} touch at point {} {}", f, g, c.point,
                              xy(P.p[c.point])));
    case Crossing::Kind::cross: break;
  }
  const K::Segment_2 sf(P.p[P.seg(f)[0]], P.p[P.seg(f)[1]]), sg(P.p[P.seg(g)[0]], P.p[P.seg(g)[1]]);
  std::string where;
  if (auto x = CGAL::intersection(sf, sg))
    if (const auto* q = boost::get<K::Point_2>(&*x)) where = " near " + xy(*q);
  return fail(fmt::format("self-intersecting polygon: segments {} and {} intersect{}", f, g, where));
}

std::optional<BoundaryCheck> check_counter_clockwise(const Polygon& P) {
  double area2 = 0;
  for (std::int64_t f = 0; f < P.m; ++f) {
    const auto& a = P.p[P.seg(f)[0]];
    const auto& c = P.p[P.seg(f)[1]];
    area2 += a.x() * c.y() - a.y() * c.x();
  }
  if (area2 > 0) return std::nullopt;
  return fail(fmt::format("clockwise polygon: signed area {:.6g} (counter-clockwise, i.e. positive area, required)",
                          0.5 * area2));
}

/// A simple, closed, counter-clockwise polygon; the first check that fails names what and where.
BoundaryCheck check_polygon(const Boundary& b) {
  if (auto r = check_arrays(b, "segment", 3)) return *r;
  Polygon P{b, b.n_points(), b.n_facets(), {}};
  P.p.resize(std::size_t(P.n));
  for (std::int64_t i = 0; i < P.n; ++i) P.p[i] = {b.points[2 * i], b.points[2 * i + 1]};
  for (auto check : {check_segments, check_one_cycle, check_polygon_intersections, check_counter_clockwise})
    if (auto r = check(P)) return *r;
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

// ---- 3D ---------------------------------------------------------------------------------------

using Check = std::optional<BoundaryCheck>;

/// A closed triangle surface as the 3D checks see it.
struct Surface {
  std::int64_t n, m;           // points, triangles
  std::vector<K::Point_3> p;   // the points
  const int* F;                // triangle t is F[3t], F[3t+1], F[3t+2]
  const std::vector<int>& facets;
};

Check check_points_used(const Surface& s) {
  std::vector<char> used(std::size_t(s.n), 0);
  for (int v : s.facets) used[v] = 1;
  for (std::int64_t v = 0; v < s.n; ++v)
    if (!used[v]) return fail(fmt::format("point {} is used by no triangle", v));
  return std::nullopt;
}

Check check_triangles(const Surface& s) {
  for (std::int64_t f = 0; f < s.m; ++f) {
    const int a = s.F[3 * f], c = s.F[3 * f + 1], d = s.F[3 * f + 2];
    if (a == c || c == d || d == a)
      return fail(fmt::format("degenerate triangle {}: it repeats point {}", f, a == c || a == d ? a : c));
    if (CGAL::collinear(s.p[a], s.p[c], s.p[d]))
      return fail(fmt::format("degenerate triangle {}: zero area (points {}, {}, {} are collinear)", f, a, c, d));
  }
  return std::nullopt;
}

struct HalfEdge {
  std::uint64_t key;
  std::int64_t facet;
  int from, to;
};

/// The 3m half-edges sorted by their undirected key (then by facet).
std::vector<HalfEdge> sorted_half_edges(const Surface& s) {
  std::vector<HalfEdge> he(std::size_t(3 * s.m));
  for (std::int64_t f = 0; f < s.m; ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = s.F[3 * f + k], c = s.F[3 * f + (k + 1) % 3];
      const auto lo = std::uint64_t(std::min(a, c)), hi = std::uint64_t(std::max(a, c));
      he[std::size_t(3 * f + k)] = {(lo << 32) | hi, f, a, c};
    }
  std::sort(he.begin(), he.end(), [](const HalfEdge& x, const HalfEdge& y) {
    return x.key != y.key ? x.key < y.key : x.facet < y.facet;
  });
  return he;
}

/// Every edge shared by exactly two triangles running along it in opposite directions; the
/// message names the offending edge of lowest triangle index.
Check check_edges(const Surface& s) {
  const std::vector<HalfEdge> he = sorted_half_edges(s);
  std::int64_t n_open = 0;
  const HalfEdge *first_open = nullptr, *first_nonmanifold = nullptr, *first_flip = nullptr, *flip_other = nullptr;
  std::size_t nonmanifold_count = 0, nonmanifold_at = 0;
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
    } else if (he[i].from == he[i + 1].from && (!first_flip || he[i].facet < first_flip->facet)) {
      first_flip = &he[i];
      flip_other = &he[i + 1];
    }
    i = j;
  }
  if (n_open > 0)
    return fail(fmt::format(
        "open surface: {} boundary edge{} (first at points {}-{} of triangle {}); a closed surface has none", n_open,
        n_open == 1 ? "" : "s", first_open->from, first_open->to, first_open->facet));
  if (first_nonmanifold) {
    std::string list;
    for (std::size_t k = 0; k < nonmanifold_count; ++k)
      list += (k ? ", " : "") + std::to_string(he[nonmanifold_at + k].facet);
    return fail(fmt::format("non-manifold edge: points {} and {} are shared by {} triangles ({}); exactly 2 allowed",
                            std::min(first_nonmanifold->from, first_nonmanifold->to),
                            std::max(first_nonmanifold->from, first_nonmanifold->to), nonmanifold_count, list));
  }
  if (first_flip)
    return fail(fmt::format(
        "inconsistent orientation: triangles {} and {} both run along edge {}->{} (each edge must be traversed once "
        "in each direction)",
        first_flip->facet, flip_other->facet, first_flip->from, first_flip->to));
  return std::nullopt;
}

using Link = std::pair<int, int>;

/// The number of separate fans in the sorted link [lb, le) of a point (1 for a manifold point).
int count_fans(const Link* lb, const Link* le) {
  const std::int64_t k = le - lb;
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
  return n_fans;
}

/// Whether the sorted link [lb, le) (edges b->c of the triangles (v, b, c)) is one cycle.
bool one_cycle(const Link* lb, const Link* le) {
  const std::int64_t k = le - lb;
  std::int64_t steps = 0;
  int w = lb->first;
  do {  // follow the link cycle through the first triangle
    auto it = std::lower_bound(lb, le, std::make_pair(w, std::numeric_limits<int>::min()));
    if (it == le || it->first != w) break;  // cannot happen for a closed oriented surface
    w = it->second;
    ++steps;
  } while (w != lb->first && steps <= k);
  return steps == k;
}

/// Vertex-manifold: the link of every point is one cycle.
Check check_vertex_links(const Surface& s) {
  std::vector<std::int64_t> start(std::size_t(s.n) + 1, 0);
  for (int v : s.facets) ++start[std::size_t(v) + 1];
  for (std::int64_t v = 0; v < s.n; ++v) start[v + 1] += start[v];
  std::vector<Link> link(s.facets.size());
  std::vector<std::int64_t> fill(start.begin(), start.end() - 1);
  for (std::int64_t f = 0; f < s.m; ++f)
    for (int k = 0; k < 3; ++k)
      link[std::size_t(fill[s.F[3 * f + k]]++)] = {s.F[3 * f + (k + 1) % 3], s.F[3 * f + (k + 2) % 3]};
  for (std::int64_t v = 0; v < s.n; ++v) {
    Link* lb = link.data() + start[v];
    Link* le = link.data() + start[v + 1];
    std::sort(lb, le);
    if (!one_cycle(lb, le))
      return fail(fmt::format("non-manifold vertex: the {} triangles around point {} {} form {} separate fans (one "
                              "allowed)",
                              le - lb, v, xyz(s.p[v]), count_fans(lb, le)));
  }
  return std::nullopt;
}

Check check_connected(const Surface& s) {
  UnionFind uf{std::size_t(s.n)};
  for (std::int64_t f = 0; f < s.m; ++f) {
    uf.unite(s.F[3 * f], s.F[3 * f + 1]);
    uf.unite(s.F[3 * f], s.F[3 * f + 2]);
  }
  std::vector<std::int64_t> size(std::size_t(s.n), 0);
  for (std::int64_t f = 0; f < s.m; ++f) ++size[uf.find(s.F[3 * f])];
  std::vector<std::int64_t> sizes;
  for (auto z : size)
    if (z > 0) sizes.push_back(z);
  if (sizes.size() <= 1) return std::nullopt;
  std::sort(sizes.rbegin(), sizes.rend());
  std::string list;
  for (std::size_t k = 0; k < std::min<std::size_t>(sizes.size(), 5); ++k)
    list += (k ? ", " : "") + std::to_string(sizes[k]);
  if (sizes.size() > 5) list += ", ...";
  return fail(fmt::format("{} connected components ({} triangles); one closed surface allowed", sizes.size(), list));
}

Check check_outward(const Surface& s) {
  double vol6 = 0;
  for (std::int64_t f = 0; f < s.m; ++f) {
    const auto& a = s.p[s.F[3 * f]];
    const auto& c = s.p[s.F[3 * f + 1]];
    const auto& d = s.p[s.F[3 * f + 2]];
    vol6 += a.x() * (c.y() * d.z() - c.z() * d.y()) - a.y() * (c.x() * d.z() - c.z() * d.x()) +
            a.z() * (c.x() * d.y() - c.y() * d.x());
  }
  if (vol6 > 0) return std::nullopt;
  return fail(fmt::format(
      "inward orientation: the enclosed volume is {:.6g} (outward normals, i.e. positive volume, required)", vol6 / 6));
}

/// Self-intersections (exact predicates), on a halfedge structure.
Check check_self_intersections(const Surface& s) {
  using Mesh = CGAL::Surface_mesh<K::Point_3>;
  Mesh mesh;
  mesh.reserve(Mesh::size_type(s.n), Mesh::size_type(3 * s.m / 2), Mesh::size_type(s.m));
  for (const auto& q : s.p) mesh.add_vertex(q);
  for (std::int64_t f = 0; f < s.m; ++f) {
    const auto fd = mesh.add_face(Mesh::Vertex_index(s.F[3 * f]), Mesh::Vertex_index(s.F[3 * f + 1]),
                                  Mesh::Vertex_index(s.F[3 * f + 2]));
    if (fd == Mesh::null_face())  // not expected after the checks above
      return fail(fmt::format("non-manifold surface at triangle {}", f));
  }
  std::vector<std::pair<Mesh::Face_index, Mesh::Face_index>> pairs;
  CGAL::Polygon_mesh_processing::self_intersections(faces(mesh), mesh, std::back_inserter(pairs),
                                                    CGAL::parameters::maximum_number(1));
  if (pairs.empty()) return std::nullopt;
  std::int64_t i = pairs.front().first.idx(), j = pairs.front().second.idx();
  if (i > j) std::swap(i, j);
  return fail(fmt::format("self-intersecting surface: triangles {} and {} intersect", i, j));
}

/// A closed, oriented (outward), manifold, connected, self-intersection-free triangle surface;
/// the first check that fails names what and where.
BoundaryCheck check_surface(const Boundary& b) {
  if (auto r = check_arrays(b, "triangle", 4)) return *r;
  Surface s{b.n_points(), b.n_facets(), {}, b.facets.data(), b.facets};
  s.p.resize(std::size_t(s.n));
  for (std::int64_t i = 0; i < s.n; ++i) s.p[i] = {b.points[3 * i], b.points[3 * i + 1], b.points[3 * i + 2]};
  for (auto check : {check_points_used, check_triangles, check_edges, check_vertex_links, check_connected,
                     check_outward, check_self_intersections})
    if (auto r = check(s)) return *r;
  return {true, {}};
}

}  // namespace

BoundaryCheck check_boundary(const Boundary& b) {
  if (b.dim == 2) return check_polygon(b);
  if (b.dim == 3) return check_surface(b);
  return fail(fmt::format("boundary of dimension {} (2 or 3 allowed)", b.dim));
}

}  // namespace hypershape::geometry
