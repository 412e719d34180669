#include "hypershape/geometry/surface_remesh.hpp"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/remesh.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/boost/graph/Euler_operations.h>
#include <CGAL/boost/graph/helpers.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace hypershape::geometry {

namespace {

namespace PMP = CGAL::Polygon_mesh_processing;
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = K::Point_3;
using Vector = K::Vector_3;
using Mesh = CGAL::Surface_mesh<Point>;
using VI = Mesh::Vertex_index;
using HI = Mesh::Halfedge_index;
using EI = Mesh::Edge_index;
using FI = Mesh::Face_index;

Mesh to_mesh(const Boundary& s) {
  if (s.dim != 3) throw std::invalid_argument("remesh_surface: the surface must be 3D");
  if (s.points.size() % 3 != 0 || s.facets.size() % 3 != 0 || s.n_facets() < 4)
    throw std::invalid_argument("remesh_surface: malformed surface arrays");
  Mesh m;
  const std::int64_t n = s.n_points();
  for (std::int64_t i = 0; i < n; ++i)
    m.add_vertex(Point(s.points[3 * i], s.points[3 * i + 1], s.points[3 * i + 2]));
  for (std::int64_t f = 0; f < s.n_facets(); ++f) {
    const auto t = s.facet(f);
    for (int k = 0; k < 3; ++k)
      if (t[k] < 0 || t[k] >= n)
        throw std::invalid_argument("remesh_surface: triangle " + std::to_string(f) +
                                    " refers to a missing point");
    if (m.add_face(VI(t[0]), VI(t[1]), VI(t[2])) == Mesh::null_face())
      throw std::invalid_argument("remesh_surface: the surface is not a 2-manifold at triangle " +
                                  std::to_string(f) + " (check_boundary says why)");
  }
  if (!CGAL::is_closed(m))
    throw std::invalid_argument(
        "remesh_surface: the surface is not closed (check_boundary says "
        "why)");
  return m;
}

Boundary to_boundary(Mesh& m) {
  m.collect_garbage();
  Boundary b;
  b.dim = 3;
  b.points.reserve(3 * m.number_of_vertices());
  for (VI v : m.vertices()) {
    const Point& p = m.point(v);
    b.points.insert(b.points.end(), {p.x(), p.y(), p.z()});
  }
  b.facets.reserve(3 * m.number_of_faces());
  for (FI f : m.faces())
    for (VI v : CGAL::vertices_around_face(m.halfedge(f), m)) b.facets.push_back(int(v.idx()));
  return b;
}

/// Splits the edge of `h` at `x` and connects the new vertex to the opposite vertex of each
/// incident triangle (so every face stays a triangle). Returns the new vertex.
VI split_edge_at(Mesh& m, HI h, const Point& x) {
  const HI hnew = CGAL::Euler::split_edge(h, m);  // source(h) -> vnew -> target(h)
  const VI vnew = m.target(hnew);
  m.point(vnew) = x;
  const HI hnew_opp = m.opposite(hnew);
  if (!m.is_border(hnew)) CGAL::Euler::split_face(hnew, m.next(m.next(hnew)), m);
  if (!m.is_border(hnew_opp)) CGAL::Euler::split_face(m.prev(hnew_opp), m.next(hnew_opp), m);
  return vnew;
}

using Primitive = CGAL::AABB_triangle_primitive<K, std::vector<K::Triangle_3>::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;

std::vector<K::Triangle_3> triangles_of(const Mesh& m) {
  std::vector<K::Triangle_3> out;
  out.reserve(m.number_of_faces());
  for (FI f : m.faces()) {
    Point p[3];
    int k = 0;
    for (VI v : CGAL::vertices_around_face(m.halfedge(f), m)) p[k++] = m.point(v);
    out.emplace_back(p[0], p[1], p[2]);
  }
  return out;
}

/// RemeshOptions::size: remeshes the faces that want a finer edge, level by level, with
/// `remesh(faces, t)`; after each level projects every vertex but those `keep` names onto `input`
/// (the remesher projects onto the surface it was given, here the coarser level's chords) and
/// calls `after_level()`.
template <class Remesh, class Keep, class After>
void refine_locally(Mesh& m, const RemeshOptions& opt, const std::vector<K::Triangle_3>& input, Remesh&& remesh,
                    Keep&& keep, After&& after_level) {
  if (!opt.size) return;
  std::optional<Tree> tree;
  for (double t = 0.5 * opt.target_edge; t >= opt.min_edge; t *= 0.5) {
    std::vector<FI> selected;
    for (FI f : m.faces()) {
      std::array<double, 3> x{0, 0, 0};
      for (VI v : CGAL::vertices_around_face(m.halfedge(f), m))
        for (int k = 0; k < 3; ++k) x[k] += m.point(v)[k] / 3.0;
      if (opt.size(x) < 1.5 * t) selected.push_back(f);
    }
    if (selected.empty()) break;
    remesh(selected, t);
    if (!tree) {
      tree.emplace(input.begin(), input.end());
      tree->accelerate_distance_queries();
    }
    for (VI v : m.vertices())
      if (!keep(v)) m.point(v) = tree->closest_point(m.point(v));
    after_level();
  }
}

Vector face_normal(const Mesh& m, HI h) {
  const Point& a = m.point(m.source(h));
  const Point& b = m.point(m.target(h));
  const Point& c = m.point(m.target(m.next(h)));
  return CGAL::cross_product(b - a, c - a);
}

/// The cut of a surface mesh along the clamp sphere |x - c| = r and its remeshing with the cut
/// curve as a constraint: remesh_with_clamp's steps, in the order it calls them.
class ClampCut {
 public:
  ClampCut(Mesh& m, const RemeshOptions& opt)
      : m_(m), opt_(opt), c_((*opt.clamp_center)[0], (*opt.clamp_center)[1], (*opt.clamp_center)[2]),
        r_(opt.clamp_radius), h_(opt.target_edge), snap_(std::max(1e-3 * h_, 1e-8 * r_)),
        tiny_(1e-15 * std::max(r_, 1.0)) {}

  /// Resolves the cut at the target scale: no edge longer than the remesher's split threshold
  /// (exact: midpoints of straight edges). Then every curve edge, a chord of one of these
  /// triangles, is short enough that the remesher never splits it, only collapses it (keeping
  /// one of its ends, which are on the sphere). PMP::split_long_edges does not re-check the
  /// edges it creates inside the split triangles, hence the passes. 1% below the threshold leaves
  /// room for the snapping below.
  void split_long_edges() {
    const double high = 0.99 * 4.0 / 3.0 * h_;
    for (int pass = 0; pass < 64; ++pass) {
      std::vector<EI> long_edges;
      for (EI e : m_.edges())
        if (CGAL::squared_distance(m_.point(m_.source(m_.halfedge(e))), m_.point(m_.target(m_.halfedge(e)))) >
            high * high)
          long_edges.push_back(e);
      if (long_edges.empty()) break;
      PMP::split_long_edges(long_edges, high, m_);
    }
  }

  /// Which side of the sphere each vertex is on: -1 inside, 0 on (snapped), +1 outside.
  void mark_sides() {
    side_ = m_.add_property_map<VI, int>("v:hs_side", 0).first;
    for (VI v : m_.vertices()) {
      const double d = std::sqrt(CGAL::squared_distance(m_.point(v), c_));
      if (std::abs(d - r_) <= snap_) {
        m_.point(v) = on_sphere(m_.point(v));
        side_[v] = 0;
      } else {
        side_[v] = d < r_ ? -1 : 1;
      }
    }
  }

  /// An edge with no endpoint inside may still pass through the ball (a "dip"): split it where
  /// it comes closest to the centre, so that every edge crosses the sphere at most once.
  void split_dips() {
    std::vector<EI> snapshot(m_.edges().begin(), m_.edges().end());
    for (EI e : snapshot) {
      const HI he = m_.halfedge(e);
      const VI a = m_.source(he), b = m_.target(he);
      if (side_[a] < 0 || side_[b] < 0 || (side_[a] == 0 && side_[b] == 0)) continue;
      const Point &pa = m_.point(a), &pb = m_.point(b);
      const Vector d = pb - pa;
      const double t = ((c_ - pa) * d) / d.squared_length();
      if (!(t > 1e-6 && t < 1 - 1e-6)) continue;
      const Point q = pa + t * d;
      if (std::sqrt(CGAL::squared_distance(q, c_)) >= r_ - snap_) continue;
      side_[split_edge_at(m_, he, q)] = -1;
    }
  }

  /// Splits every edge whose endpoints are on opposite sides at its crossing point.
  void split_crossings() {
    std::vector<EI> snapshot(m_.edges().begin(), m_.edges().end());
    for (EI e : snapshot) {
      const HI he = m_.halfedge(e);
      const VI a = m_.source(he), b = m_.target(he);
      if (side_[a] * side_[b] >= 0) continue;
      const Point &pa = m_.point(a), &pb = m_.point(b);
      const Vector d = pb - pa, w = pa - c_;
      // |w + t d|^2 = r^2: exactly one root in (0, 1) since the ends are on opposite sides.
      const double A = d * d, B = 2 * (w * d), C = w * w - r_ * r_;
      const double disc = std::sqrt(std::max(0.0, B * B - 4 * A * C));
      const double q = -0.5 * (B + std::copysign(disc, B));
      double t1 = q / A, t2 = q != 0 ? C / q : t1;
      auto dist01 = [](double t) { return t < 0 ? -t : (t > 1 ? t - 1 : 0.0); };
      const double t = std::clamp(dist01(t1) <= dist01(t2) ? t1 : t2, 0.0, 1.0);
      side_[split_edge_at(m_, he, on_sphere(pa + t * d))] = 0;
    }
  }

  /// The patch: faces with no vertex outside (so facets_in_ball finds exactly them). The curve:
  /// edges between a patch face and another face; both ends of such an edge are on the sphere.
  /// Then the input surface near the curve, for moving new curve vertices back onto it.
  void mark_patch_and_curve() {
    patch_ = m_.add_property_map<FI, int>("f:hs_patch", 0).first;
    for (FI f : m_.faces()) {
      bool outside = false;
      for (VI v : CGAL::vertices_around_face(m_.halfedge(f), m_)) outside |= side_[v] > 0;
      patch_[f] = outside ? 0 : 1;
    }
    constrained_ = m_.add_property_map<EI, bool>("e:hs_clamp", false).first;
    for (EI e : m_.edges()) {
      const HI he = m_.halfedge(e);
      if (patch_[m_.face(he)] != patch_[m_.face(m_.opposite(he))]) {
        constrained_[e] = true;
        ++n_curve_;
      }
    }
    if (n_curve_ > 0) collect_band();
  }

  /// The isotropic remeshing at h with the curve constrained, then the local refinement (if
  /// asked for), the curve snapped back after each.
  void remesh(const std::vector<K::Triangle_3>& input) {
    remesh_faces(faces(m_), h_);
    if (n_curve_ > 0) snap_curve();
    refine_locally(
        m_, opt_, input, [&](const std::vector<FI>& selected, double t) { remesh_faces(selected, t); },
        [&](VI v) { return on_curve(v); },
        [&] {
          if (n_curve_ > 0) snap_curve();
        });
  }

  /// A vertex off the curve on the outer side could sit inside the ball (within the sagitta of
  /// a curve edge); push it just outside so that every outer face has a vertex outside the ball.
  void push_outer_vertices() {
    if (n_curve_ == 0) return;
    for (FI f : m_.faces()) {
      if (patch_[f] != 0) continue;
      bool has_outside = false;
      for (VI v : CGAL::vertices_around_face(m_.halfedge(f), m_))
        has_outside |= std::sqrt(CGAL::squared_distance(m_.point(v), c_)) > r_ * (1 + 1e-9);
      if (has_outside) continue;
      for (VI v : CGAL::vertices_around_face(m_.halfedge(f), m_)) {
        if (on_curve(v)) continue;
        const Vector u = m_.point(v) - c_;
        m_.point(v) = c_ + u * (r_ * (1 + 1e-6) / std::sqrt(u.squared_length()));
        has_outside = true;
        break;
      }
      if (!has_outside)
        throw std::runtime_error(
            "remesh_surface: a triangle outside the clamp patch has all its "
            "vertices on the clamp curve; the target edge is too coarse for "
            "the clamp radius");
    }
  }

 private:
  Point on_sphere(const Point& x) const {
    const Vector u = x - c_;
    const double d = std::sqrt(u.squared_length());
    return d > 0 ? c_ + u * (r_ / d) : x;
  }
  bool on_curve(VI v) const {
    for (HI he : CGAL::halfedges_around_target(v, m_))
      if (constrained_[m_.edge(he)]) return true;
    return false;
  }
  template <class FaceRange>
  void remesh_faces(const FaceRange& selected, double edge) {
    PMP::isotropic_remeshing(selected, edge, m_,
                             CGAL::parameters::number_of_iterations(unsigned(opt_.iterations))
                                 .edge_is_constrained_map(constrained_)
                                 .face_patch_map(patch_)
                                 .protect_constraints(false)
                                 .collapse_constraints(true)
                                 .relax_constraints(false));
  }
  void collect_band() {
    for (FI f : m_.faces()) {
      double dmin = 1e300, dmax = 0, lmax = 0;
      Point p[3];
      int k = 0;
      for (VI v : CGAL::vertices_around_face(m_.halfedge(f), m_)) p[k++] = m_.point(v);
      for (int i = 0; i < 3; ++i) {
        const double d = std::sqrt(CGAL::squared_distance(p[i], c_));
        dmin = std::min(dmin, d);
        dmax = std::max(dmax, d);
        lmax = std::max(lmax, std::sqrt(CGAL::squared_distance(p[i], p[(i + 1) % 3])));
      }
      if (dmin - lmax <= r_ + 2 * h_ && dmax >= r_ - 2 * h_) band_.emplace_back(p[0], p[1], p[2]);
    }
  }
  /// Should the remesher have split a constrained edge, the new vertex is at its midpoint (inside
  /// the ball, off the surface-sphere intersection). Moves each such vertex to where the input
  /// surface meets the sphere by alternating projections (they converge fast: the two surfaces
  /// cross at a clear angle for a patch centred on the surface). Done after every remesh: a curve
  /// vertex moved only after several levels of refinement would fold the small triangles around it.
  void snap_curve() {
    for (VI v : m_.vertices()) {
      if (!on_curve(v)) continue;
      const Point x0 = m_.point(v);
      if (std::abs(std::sqrt(CGAL::squared_distance(x0, c_)) - r_) <= 4 * tiny_) {
        m_.point(v) = on_sphere(x0);
        continue;
      }
      std::vector<std::pair<HI, Vector>> normals;
      for (HI he : CGAL::halfedges_around_target(v, m_))
        if (!m_.is_border(he)) normals.emplace_back(he, face_normal(m_, he));
      m_.point(v) = project_to_curve(x0);
      for (auto& [he, n0] : normals)
        if (face_normal(m_, he) * n0 <= 0)
          throw std::runtime_error(
              "remesh_surface: moving a clamp-curve vertex onto the sphere "
              "folds a triangle; the target edge is too coarse for the clamp "
              "radius");
    }
  }
  Point project_to_curve(const Point& x0) {
    if (!tree_) {  // built on first use: normally no vertex needs moving
      tree_.emplace(band_.begin(), band_.end());
      tree_->accelerate_distance_queries();
    }
    Point x = on_sphere(x0);
    for (int it = 0; it < 200; ++it) {
      const Point xn = on_sphere(tree_->closest_point(x));
      const double step = std::sqrt(CGAL::squared_distance(xn, x));
      x = xn;
      if (step <= tiny_) break;
    }
    return x;
  }

  Mesh& m_;
  const RemeshOptions& opt_;
  Point c_;
  double r_, h_, snap_, tiny_;
  Mesh::Property_map<VI, int> side_;
  Mesh::Property_map<FI, int> patch_;
  Mesh::Property_map<EI, bool> constrained_;
  std::size_t n_curve_ = 0;
  std::vector<K::Triangle_3> band_;  // the input surface near the curve
  std::optional<Tree> tree_;
};

/// Cuts `m` along the sphere |x - c| = r and remeshes it with the cut curve as a constraint.
void remesh_with_clamp(Mesh& m, const RemeshOptions& opt, const std::vector<K::Triangle_3>& input) {
  ClampCut cut(m, opt);
  cut.split_long_edges();
  cut.mark_sides();
  cut.split_dips();
  cut.split_crossings();
  cut.mark_patch_and_curve();
  cut.remesh(input);
  cut.push_outer_vertices();
}

}  // namespace

Boundary remesh_surface(const Boundary& surface, const RemeshOptions& opt) {
  if (!(opt.target_edge > 0) || !std::isfinite(opt.target_edge))
    throw std::invalid_argument("remesh_surface: target_edge must be positive and finite");
  if (opt.iterations < 1) throw std::invalid_argument("remesh_surface: iterations must be >= 1");
  if (opt.clamp_center && !(opt.clamp_radius > 0 && std::isfinite(opt.clamp_radius)))
    throw std::invalid_argument("remesh_surface: clamp_radius must be positive and finite");
  if (opt.size && !(opt.min_edge > 0)) throw std::invalid_argument("remesh_surface: min_edge must be positive");
  Mesh m = to_mesh(surface);
  const std::vector<K::Triangle_3> input = opt.size ? triangles_of(m) : std::vector<K::Triangle_3>{};
  if (opt.clamp_center) {
    remesh_with_clamp(m, opt, input);
  } else {
    auto remesh = [&](const auto& selected, double t) {
      PMP::isotropic_remeshing(selected, t, m, CGAL::parameters::number_of_iterations(unsigned(opt.iterations)));
    };
    remesh(faces(m), opt.target_edge);
    refine_locally(m, opt, input, remesh, [](VI) { return false; }, [] {});
  }
  return to_boundary(m);
}

std::vector<int> facets_in_ball(const Boundary& b, const std::array<double, 3>& center,
                                double radius) {
  std::vector<int> out;
  const double r2 = radius * (1 + 1e-9) * radius * (1 + 1e-9);
  for (std::int64_t f = 0; f < b.n_facets(); ++f) {
    bool inside = true;
    for (int v : b.facet(f)) {
      double d2 = 0;
      for (int k = 0; k < b.dim; ++k) {
        const double dx = b.points[std::size_t(v) * b.dim + k] - center[k];
        d2 += dx * dx;
      }
      inside &= d2 <= r2;
    }
    if (inside) out.push_back(int(f));
  }
  return out;
}

}  // namespace hypershape::geometry
