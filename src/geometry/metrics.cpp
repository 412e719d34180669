#include "hypershape/geometry/metrics.hpp"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <limits>
#include <numbers>
#include <span>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "aabb.hpp"
#include "hypershape/core/vec3.hpp"

namespace hypershape::geometry {
namespace {

using Vec = core::Vec3;
using core::cross, core::dot, core::sub;

double norm2(const Vec& a) { return dot(a, a); }
Vec midpoint(const Vec& a, const Vec& b) {
  return {0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2])};
}

void check_dim(const Boundary& b, const char* what) {
  if (b.dim != 2 && b.dim != 3)
    throw std::invalid_argument(std::string(what) + ": boundary dimension must be 2 or 3, got " +
                                std::to_string(b.dim));
}

/// Point i as a 3-vector (z = 0 in 2D).
Vec point3(const Boundary& b, std::int64_t i) {
  const auto p = b.point(i);
  return {p[0], p[1], b.dim == 3 ? p[2] : 0.0};
}

/// Outward normal of facet f scaled by its measure (length in 2D, area in 3D).
Vec facet_normal(const Boundary& b, std::int64_t f) {
  const auto v = b.facet(f);
  const Vec a = point3(b, v[0]), c = point3(b, v[1]);
  if (b.dim == 2) return {c[1] - a[1], a[0] - c[0], 0.0};  // (c - a) rotated clockwise
  const Vec d = point3(b, v[2]);
  const Vec n = cross(sub(c, a), sub(d, a));
  return {0.5 * n[0], 0.5 * n[1], 0.5 * n[2]};
}

// ---- shrinking ball ---------------------------------------------------------------------------

/// What the shrinking-ball search needs of every facet and point of a boundary.
///
/// Two vertex normals; which one is used depends on whether the vertex is a corner.
///  - smooth: Max's weights (N. Max, J. Graphics Tools 4(2), 1999), the facet normal divided by
///    the squared lengths of the facet's edges at the vertex (one edge in 2D): exact whenever the
///    vertex and its neighbours lie on a common circle / sphere. The area-weighted normal is off
///    by about 1 degree on an icosphere, which shrinks its balls to 0.8 R (measured): the balls
///    are tangent to the normal, so a tilt lets the nearby samples in.
///  - corner: unit facet normals weighted by the facet angle at the vertex (1 in 2D), the
///    bisector whatever the lengths of the sides; Max's weights would follow the shorter side.
struct BallFrame {
  std::vector<Vec> smooth_normal, corner_normal;  // per point
  std::vector<Vec> unit_normal;                   // per facet
  std::vector<double> diameter;                   // per facet: its longest edge
  std::vector<std::int64_t> start, incident;      // point -> facets (CSR)
  std::vector<std::int64_t> region;               // per facet: its flat region

  std::span<const std::int64_t> incident_to(std::int64_t i) const {
    return {incident.data() + start[std::size_t(i)], incident.data() + start[std::size_t(i) + 1]};
  }
};

/// The normals and diameter of facet f, added to its points' vertex normals.
void add_facet(const Boundary& b, std::int64_t f, BallFrame& fr) {
  const int dim = b.dim;
  const Vec n = facet_normal(b, f);
  const double len = std::sqrt(norm2(n));
  const Vec u = len > 0 ? Vec{n[0] / len, n[1] / len, n[2] / len} : Vec{0, 0, 0};
  fr.unit_normal[std::size_t(f)] = u;
  const auto v = b.facet(f);
  double& diameter = fr.diameter[std::size_t(f)];
  for (int i = 0; i < dim; ++i) {
    const auto vi = std::size_t(v[std::size_t(i)]);
    const Vec x = point3(b, std::int64_t(vi));
    ++fr.start[vi + 1];
    const Vec e1 = sub(point3(b, v[std::size_t((i + 1) % dim)]), x);
    const Vec e2 = dim == 3 ? sub(point3(b, v[std::size_t((i + 2) % dim)]), x) : e1;
    const double weight = dim == 3 ? norm2(e1) * norm2(e2) : norm2(e1);
    const double angle = dim == 3 ? std::atan2(std::sqrt(norm2(cross(e1, e2))), dot(e1, e2)) : 1.0;
    for (int k = 0; k < 3; ++k) {
      if (weight > 0) fr.smooth_normal[vi][std::size_t(k)] += n[std::size_t(k)] / weight;
      fr.corner_normal[vi][std::size_t(k)] += angle * u[std::size_t(k)];
    }
    for (int j = i + 1; j < dim; ++j) diameter = std::max(diameter, norm2(sub(x, point3(b, v[std::size_t(j)]))));
  }
  diameter = std::sqrt(diameter);
}

/// Flat regions: maximal sets of facets, connected through shared vertices (2D) / edges (3D),
/// with the same normal (the straight side of a polygon, the face of a box). The regions of the
/// facets at p are ignored, not only those facets: where the boundary is smooth at p they are
/// tangent to every candidate ball anyway, and at a convex corner (where the exact medial ball
/// is 0) the ball then grows along the bisector until it meets the rest of the shape, the same
/// for any sampling of the sides.
std::vector<std::int64_t> flat_regions(const Boundary& b, const BallFrame& fr) {
  const int dim = b.dim;
  std::vector<std::int64_t> region(std::size_t(b.n_facets()));
  for (std::int64_t f = 0; f < b.n_facets(); ++f) region[std::size_t(f)] = f;
  const auto find = [&](std::int64_t f) {
    while (region[std::size_t(f)] != f) f = region[std::size_t(f)] = region[std::size_t(region[std::size_t(f)])];
    return f;
  };
  for (std::int64_t f = 0; f < b.n_facets(); ++f) {
    const auto v = b.facet(f);
    for (int i = 0; i < dim; ++i) {
      const int a = v[std::size_t(i)], c = v[std::size_t((i + 1) % dim)];
      for (const std::int64_t g : fr.incident_to(a)) {
        if (g <= f) continue;
        const auto w = b.facet(g);
        if (dim == 3 && std::find(w.begin(), w.end(), c) == w.end()) continue;  // no shared edge
        if (dot(fr.unit_normal[std::size_t(f)], fr.unit_normal[std::size_t(g)]) < 1 - 1e-12) continue;
        region[std::size_t(find(f))] = find(g);
      }
    }
  }
  for (std::int64_t f = 0; f < b.n_facets(); ++f) region[std::size_t(f)] = find(f);
  return region;
}

BallFrame ball_frame(const Boundary& b) {
  const std::int64_t n_points = b.n_points(), n_facets = b.n_facets();
  BallFrame fr;
  fr.smooth_normal.assign(std::size_t(n_points), Vec{0, 0, 0});
  fr.corner_normal.assign(std::size_t(n_points), Vec{0, 0, 0});
  fr.unit_normal.resize(std::size_t(n_facets));
  fr.diameter.assign(std::size_t(n_facets), 0.0);
  fr.start.assign(std::size_t(n_points) + 1, 0);
  for (std::int64_t f = 0; f < n_facets; ++f) add_facet(b, f, fr);
  for (std::int64_t i = 0; i < n_points; ++i) fr.start[std::size_t(i) + 1] += fr.start[std::size_t(i)];
  fr.incident.resize(std::size_t(fr.start.back()));
  std::vector<std::int64_t> fill(fr.start.begin(), fr.start.end() - 1);
  for (std::int64_t f = 0; f < n_facets; ++f)
    for (const int v : b.facet(f)) fr.incident[std::size_t(fill[std::size_t(v)]++)] = f;
  fr.region = flat_regions(b, fr);
  return fr;
}

/// The unit normal at point i pointing into the ball's side (zero if the point is on no facet):
/// at a corner (two facets at it whose normals differ by more than 30 degrees) the bisector.
Vec ball_direction(const BallFrame& fr, std::int64_t i, bool inward) {
  bool corner = false;
  const auto at_p = fr.incident_to(i);
  for (std::size_t a = 0; a < at_p.size() && !corner; ++a)
    for (std::size_t c = a + 1; c < at_p.size() && !corner; ++c)
      corner = dot(fr.unit_normal[std::size_t(at_p[a])], fr.unit_normal[std::size_t(at_p[c])]) <
               std::cos(std::numbers::pi / 6);
  Vec n = corner ? fr.corner_normal[std::size_t(i)] : fr.smooth_normal[std::size_t(i)];
  const double len = std::sqrt(norm2(n));
  if (!(len > 0)) return {0, 0, 0};  // on no facet (or a degenerate fan)
  const double s = (inward ? -1.0 : 1.0) / len;
  for (double& component : n) component *= s;
  return n;
}

// A facet whose vertices are all outside (or on) the ball and that is short compared to the
// radius cuts into the ball by at most its sagitta: r (1 - sqrt(1 - beta^2 / 4)) <= r / 32 for
// beta = 1/2. That is how a sampled circle or sphere looks from its centre (an icosphere with
// 320 triangles has facets of 0.35 R), so it does not shrink the ball. A longer facet does:
// then the polygon/surface itself is the shape.
constexpr double beta = 0.5;
constexpr double rel_tol = 1e-9;  // contacts within this relative depth count as touching

/// The ball at point i along n, shrunk from radius `cap` until it holds no sample of the shape.
double shrink_ball(const Boundary& b, const detail::FacetTree& tree, const BallFrame& fr, std::int64_t i, const Vec& n,
                   double cap) {
  const Vec p = point3(b, i);
  std::vector<std::int64_t> own;
  for (const std::int64_t f : fr.incident_to(i)) own.push_back(fr.region[std::size_t(f)]);
  double r = cap;
  for (int iter = 0; iter < 100 && r > 0; ++iter) {
    const Vec c = {p[0] + r * n[0], p[1] + r * n[1], p[2] + r * n[2]};
    const double inner2 = (r * (1 - rel_tol)) * (r * (1 - rel_tol));
    const auto skip = [&](std::int64_t f) {
      if (std::find(own.begin(), own.end(), fr.region[std::size_t(f)]) != own.end()) return true;
      if (fr.diameter[std::size_t(f)] > beta * r) return false;
      for (const int w : b.facet(f))
        if (norm2(sub(point3(b, w), c)) < inner2) return false;
      return true;
    };
    const detail::ClosestHit hit = tree.closest_if(c.data(), inner2, skip);
    if (hit.facet < 0) break;  // the ball is empty: done
    // A short facet stands for its vertices, the samples of the shape: the ball shrinks to
    // exclude the vertex that is inside it, not the chord (which lies inside the sampled
    // surface by its sagitta, and would make the ball at a point of high curvature too small).
    Vec q = hit.point;
    if (fr.diameter[std::size_t(hit.facet)] <= beta * r) {
      double best = HUGE_VAL;
      for (const int w : b.facet(hit.facet)) {
        const Vec x = point3(b, w);
        if (const double d2 = norm2(sub(x, c)); d2 < best) best = d2, q = x;
      }
    }
    const Vec pq = sub(q, p);
    const double denom = 2 * dot(n, pq);
    // |c - q| < r implies n.(q - p) > |q - p|^2 / (2 r) > 0; a non-positive value is round-off
    // for q at p: the boundary touches itself there.
    const double r_new = denom > 0 ? norm2(pq) / denom : 0.0;
    if (!(r_new < r)) break;
    const bool converged = r - r_new <= 1e-12 * r;
    r = r_new;
    if (converged) break;
  }
  return r;
}

/// Medial-ball radii along +/- the vertex normals; `inward` picks the side (NaN for a point on
/// no facet).
std::vector<double> ball_radii(const Boundary& b, bool inward) {
  check_dim(b, inward ? "inscribed_radii" : "exterior_radii");
  const detail::FacetTree tree(b, {}, false);
  const BallFrame fr = ball_frame(b);
  std::vector<double> radii(std::size_t(b.n_points()), std::numeric_limits<double>::quiet_NaN());
  for (std::int64_t i = 0; i < b.n_points(); ++i) {
    const Vec n = ball_direction(fr, i, inward);
    if (n[0] != 0 || n[1] != 0 || n[2] != 0) radii[std::size_t(i)] = shrink_ball(b, tree, fr, i, n, tree.bbox_diagonal());
  }
  return radii;
}

// ---- Hausdorff --------------------------------------------------------------------------------

/// The directed Hausdorff distance from `from` to `to` by branch and bound: a lower bound from
/// the vertices, then every facet of `from` bisected where its upper bound could still beat the
/// lower one by more than the tolerance.
class DirectedHausdorff {
 public:
  DirectedHausdorff(const Boundary& from, const detail::FacetTree& to) : from_(from), to_(to), dim_(from.dim) {}

  double run(double tolerance) {
    vertex_pass();
    for (std::int64_t f = 0; f < from_.n_facets(); ++f) refine_facet(f, tolerance);
    return lower_;
  }

 private:
  // A simplex of `from`: vertices, their distances to `to` and the facet of `to` realising it.
  struct Simplex {
    std::array<Vec, 3> x;
    std::array<double, 3> d;
    std::array<std::int64_t, 3> f;
  };

  std::pair<double, std::int64_t> closest(const Vec& x) {
    hit_ = hit_.facet < 0 ? to_.closest(x.data()) : to_.closest(x.data(), hit_);
    return std::pair{std::sqrt(hit_.squared_distance), hit_.primitive};
  }

  /// Lower bound from the vertices first, so that most facets are pruned at once.
  void vertex_pass() {
    const std::int64_t n_points = from_.n_points();
    d_point_.assign(std::size_t(n_points), 0.0);
    f_point_.assign(std::size_t(n_points), -1);
    for (const int i : from_.facets) {
      if (f_point_[std::size_t(i)] >= 0) continue;
      std::tie(d_point_[std::size_t(i)], f_point_[std::size_t(i)]) = closest(point3(from_, i));
      lower_ = std::max(lower_, d_point_[std::size_t(i)]);
    }
  }

  // Upper bound of dist(., to) over the simplex. Two bounds, both valid for every x in it:
  //  - Lipschitz: dist(x) <= d_i + |x - v_i| <= d_i + max_j |v_j - v_i|;
  //  - convexity: dist(x) <= dist(x, F_i) for the facet F_i closest to v_i, and dist(., F_i) is
  //    convex, so its max over the simplex is at a vertex. This one is tight where the two
  //    boundaries run parallel (a shape and its offset), where Lipschitz alone would bisect
  //    every facet down to the tolerance.
  // diam2, e0, e1: the squared length of the longest edge and its ends.
  double upper_bound(const Simplex& t, double& diam2, int& e0, int& e1) const {
    double upper = std::numeric_limits<double>::infinity();
    diam2 = 0, e0 = 0, e1 = 1;
    for (int a = 0; a < dim_; ++a) {
      double far2 = 0, convex2 = 0;
      for (int c = 0; c < dim_; ++c) {
        const double l2 = norm2(sub(t.x[std::size_t(a)], t.x[std::size_t(c)]));
        far2 = std::max(far2, l2);
        if (l2 > diam2) diam2 = l2, e0 = a, e1 = c;
        convex2 = std::max(convex2, c == a ? t.d[std::size_t(a)] * t.d[std::size_t(a)]
                                           : to_.squared_distance_to(t.x[std::size_t(c)].data(),
                                                                     t.f[std::size_t(a)]));
      }
      upper = std::min({upper, t.d[std::size_t(a)] + std::sqrt(far2), std::sqrt(convex2)});
    }
    return upper;
  }

  void refine_facet(std::int64_t f, double tolerance) {
    const auto v = from_.facet(f);
    Simplex s{};
    for (int k = 0; k < dim_; ++k) {
      const auto i = std::size_t(v[std::size_t(k)]);
      s.x[std::size_t(k)] = point3(from_, std::int64_t(i));
      s.d[std::size_t(k)] = d_point_[i];
      s.f[std::size_t(k)] = f_point_[i];
    }
    std::vector<Simplex> stack{s};
    while (!stack.empty()) {
      const Simplex t = stack.back();
      stack.pop_back();
      double diam2 = 0;
      int e0 = 0, e1 = 1;
      const double upper = upper_bound(t, diam2, e0, e1);
      // Pruned either because it cannot beat `lower`, or because upper <= max_i d_i + diam <=
      // lower + tolerance: the guarantee of the header.
      if (upper <= lower_ || std::sqrt(diam2) <= tolerance) continue;
      const Vec m = midpoint(t.x[std::size_t(e0)], t.x[std::size_t(e1)]);
      const auto [dm, fm] = closest(m);
      lower_ = std::max(lower_, dm);
      Simplex c0 = t, c1 = t;  // bisect the longest edge
      c0.x[std::size_t(e0)] = m, c0.d[std::size_t(e0)] = dm, c0.f[std::size_t(e0)] = fm;
      c1.x[std::size_t(e1)] = m, c1.d[std::size_t(e1)] = dm, c1.f[std::size_t(e1)] = fm;
      stack.push_back(c0);
      stack.push_back(c1);
    }
  }

  const Boundary& from_;
  const detail::FacetTree& to_;
  const int dim_;
  detail::ClosestHit hit_;
  std::vector<double> d_point_;
  std::vector<std::int64_t> f_point_;
  double lower_ = 0;
};

double directed_hausdorff_impl(const Boundary& from, const detail::FacetTree& to, double tolerance) {
  return DirectedHausdorff(from, to).run(tolerance);
}

void check_pair(const Boundary& a, const Boundary& b, double tolerance, const char* what) {
  check_dim(a, what);
  check_dim(b, what);
  if (a.dim != b.dim)
    throw std::invalid_argument(std::string(what) + ": boundaries of dimensions " +
                                std::to_string(a.dim) + " and " + std::to_string(b.dim));
  if (!(tolerance > 0))
    throw std::invalid_argument(std::string(what) + ": tolerance must be > 0, got " +
                                std::to_string(tolerance));
}

}  // namespace

double enclosed_measure(const Boundary& b) {
  check_dim(b, "enclosed_measure");
  double sum = 0;
  for (std::int64_t f = 0; f < b.n_facets(); ++f) {
    const auto v = b.facet(f);
    const Vec p = point3(b, v[0]), q = point3(b, v[1]);
    if (b.dim == 2) {
      sum += p[0] * q[1] - p[1] * q[0];
    } else {
      sum += dot(p, cross(q, point3(b, v[2])));
    }
  }
  return sum / (b.dim == 2 ? 2.0 : 6.0);
}

double boundary_measure(const Boundary& b) {
  check_dim(b, "boundary_measure");
  double sum = 0;
  for (std::int64_t f = 0; f < b.n_facets(); ++f) sum += std::sqrt(norm2(facet_normal(b, f)));
  return sum;
}

namespace {
/// 1 for a disk (2D: 4 pi A / P^2) or a ball (3D: 36 pi V^2 / S^3), smaller for any other shape.
double isoperimetric_of(int dim, double measure, double boundary) {
  return dim == 2 ? 4 * std::numbers::pi * measure / (boundary * boundary)
                  : 36 * std::numbers::pi * measure * measure / (boundary * boundary * boundary);
}
}  // namespace

double isoperimetric_ratio(const Boundary& b) {
  check_dim(b, "isoperimetric_ratio");
  return isoperimetric_of(b.dim, enclosed_measure(b), boundary_measure(b));
}

double directed_hausdorff_distance(const Boundary& from, const Boundary& to, double tolerance) {
  check_pair(from, to, tolerance, "directed_hausdorff_distance");
  const detail::FacetTree tree(to, {}, false);
  return directed_hausdorff_impl(from, tree, tolerance);
}

double hausdorff_distance(const Boundary& a, const Boundary& b, double tolerance) {
  check_pair(a, b, tolerance, "hausdorff_distance");
  const detail::FacetTree tree_a(a, {}, false), tree_b(b, {}, false);
  return std::max(directed_hausdorff_impl(a, tree_b, tolerance),
                  directed_hausdorff_impl(b, tree_a, tolerance));
}

std::vector<double> inscribed_radii(const Boundary& b) { return ball_radii(b, true); }
std::vector<double> exterior_radii(const Boundary& b) { return ball_radii(b, false); }

ShapeMetrics compute_metrics(const Boundary& shape, const Boundary* base,
                             double hausdorff_tolerance) {
  check_dim(shape, "compute_metrics");
  const auto min_of = [](const std::vector<double>& v) {
    double m = std::numeric_limits<double>::quiet_NaN();
    for (const double x : v) m = std::fmin(m, x);  // fmin skips NaN
    return m;
  };
  ShapeMetrics m;
  m.measure = enclosed_measure(shape);
  m.boundary_measure = boundary_measure(shape);
  m.isoperimetric_ratio = isoperimetric_of(shape.dim, m.measure, m.boundary_measure);
  m.hausdorff_to_base = base ? hausdorff_distance(shape, *base, hausdorff_tolerance)
                             : std::numeric_limits<double>::quiet_NaN();
  m.n_boundary_facets = shape.n_facets();
  m.min_local_feature_size = min_of(inscribed_radii(shape));
  m.min_exterior_gap = min_of(exterior_radii(shape));
  return m;
}

}  // namespace hypershape::geometry
