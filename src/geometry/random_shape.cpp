#include "hypershape/geometry/random_shape.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>
#include <unordered_map>

namespace hypershape::geometry {

namespace {

constexpr double two_pi = 2.0 * std::numbers::pi;

/// Bounding box of n points of dimension dim.
void bounding_box(int dim, std::span<const double> pts, double* lo, double* hi) {
  for (int a = 0; a < dim; ++a) {
    lo[a] = std::numeric_limits<double>::infinity();
    hi[a] = -lo[a];
  }
  for (std::size_t i = 0; i < pts.size(); i += dim)
    for (int a = 0; a < dim; ++a) {
      lo[a] = std::min(lo[a], pts[i + a]);
      hi[a] = std::max(hi[a], pts[i + a]);
    }
}

}  // namespace

// ---- RandomDeformation --------------------------------------------------------------------

void RandomDeformation::flow(double* x) const {
  double u[3];
  for (std::size_t k = 0; k < displacements_.size(); ++k) {
    displacements_[k].evaluate(x, u);
    const auto& nrm = step_normalisation_[k];
    for (int a = 0; a < dim_; ++a) x[a] = (x[a] + u[a] - nrm[a]) * nrm[3];
  }
}

void RandomDeformation::map(double* x) const {
  flow(x);
  for (int a = 0; a < dim_; ++a) x[a] = (x[a] - center_[a]) * scale_;
}

void RandomDeformation::normalise_box(std::span<const double> lo, std::span<const double> hi) {
  double half = 0.0;
  for (int a = 0; a < dim_; ++a) {
    center_[a] = 0.5 * (lo[a] + hi[a]);
    half = std::max(half, 0.5 * (hi[a] - lo[a]));
  }
  if (!(half > 0.0)) throw std::runtime_error("degenerate shape: zero extent");
  scale_ = 1.0 / half;
}

double default_velocity_unit(int dim) { return dim == 2 ? 0.04 : 0.0125; }

RandomDeformation sample_deformation(const DeformationSpec& spec,
                                     std::span<const double> base_points,
                                     core::RandomStream& rng) {
  const int dim = spec.dim;
  assert(dim == 2 || dim == 3);
  RandomDeformation phi;
  phi.dim_ = dim;
  std::vector<double> pts(base_points.begin(), base_points.end());
  double lo[3], hi[3];
  const double nodes_per_sigma = spec.nodes_per_sigma > 0 ? spec.nodes_per_sigma : (dim == 2 ? 6.0 : 3.0);
  const double margin_sigmas = spec.margin_sigmas > 0 ? spec.margin_sigmas : (dim == 2 ? 3.0 : 1.0);
  const double unit = std::isnan(spec.velocity_unit) ? default_velocity_unit(dim) : spec.velocity_unit;
  if (!(unit >= 0.0) || !std::isfinite(unit))
    throw std::invalid_argument("velocity_unit must be finite and >= 0");
  for (const DeformationStep& step : spec.steps) {
    if (!(step.sigma > 0.0) || !(step.m >= 0.0))
      throw std::invalid_argument("deformation step needs sigma > 0 and m >= 0");
    const double std_v = step.m * unit;
    bounding_box(dim, pts, lo, hi);
    // Particles travel at most max|v| in unit time; 5 standard deviations bound max|v| over the
    // grid with overwhelming probability, and beyond the grid v is continued by a constant.
    const double margin = margin_sigmas * step.sigma + 5.0 * std_v;
    for (int a = 0; a < dim; ++a) {
      lo[a] -= margin;
      hi[a] += margin;
    }
    const Grid grid = Grid::covering(dim, {lo, std::size_t(dim)}, {hi, std::size_t(dim)},
                                     step.sigma / nodes_per_sigma);
    GridField v = sample_velocity_field(grid, step.sigma, std_v, rng);
    const int n_sq = default_squarings(v);
    phi.displacements_.push_back(exponentiate(std::move(v), n_sq));
    phi.squarings_.push_back(n_sq);
    double u[3];
    for (std::size_t i = 0; i < pts.size(); i += dim) {
      phi.displacements_.back().evaluate(&pts[i], u);
      for (int a = 0; a < dim; ++a) pts[i + a] += u[a];
    }
    // Rescale into [-1, 1]^d before the next step.
    bounding_box(dim, pts, lo, hi);
    std::array<double, 4> nrm{0, 0, 0, 0};
    double half = 0.0;
    for (int a = 0; a < dim; ++a) {
      nrm[a] = 0.5 * (lo[a] + hi[a]);
      half = std::max(half, 0.5 * (hi[a] - lo[a]));
    }
    if (!(half > 0.0)) throw std::runtime_error("degenerate shape: zero extent");
    nrm[3] = 1.0 / half;
    phi.step_normalisation_.push_back(nrm);
    for (std::size_t i = 0; i < pts.size(); i += dim)
      for (int a = 0; a < dim; ++a) pts[i + a] = (pts[i + a] - nrm[a]) * nrm[3];
  }
  bounding_box(dim, pts, lo, hi);
  phi.normalise_box({lo, std::size_t(dim)}, {hi, std::size_t(dim)});
  return phi;
}

// ---- 2D -----------------------------------------------------------------------------------

namespace {

std::array<double, 2> circle_image(const RandomDeformation& phi, double theta, bool normalised) {
  std::array<double, 2> x{std::cos(theta), std::sin(theta)};
  if (normalised)
    phi.map(x.data());
  else
    phi.flow(x.data());
  return x;
}

double turning_angle(const double* a, const double* b, const double* c) {
  const double u0 = b[0] - a[0], u1 = b[1] - a[1], w0 = c[0] - b[0], w1 = c[1] - b[1];
  return std::abs(std::atan2(u0 * w1 - u1 * w0, u0 * w0 + u1 * w1));
}

}  // namespace

CurveSamples sample_circle_image(RandomDeformation& phi, double spacing, double max_turn) {
  assert(phi.dim() == 2);
  // Work in flowed coordinates; the current normalisation only converts the spacing.
  const double flowed_spacing = spacing / phi.scale();
  std::vector<double> theta(256);
  for (std::size_t i = 0; i < theta.size(); ++i) theta[i] = two_pi * double(i) / theta.size();
  std::vector<std::array<double, 2>> x(theta.size());
  for (std::size_t i = 0; i < theta.size(); ++i) x[i] = circle_image(phi, theta[i], false);
  constexpr std::size_t max_samples = 4'000'000;
  for (int pass = 0; pass < 60; ++pass) {
    const std::size_t n = theta.size();
    std::vector<char> split(n, 0);
    bool any = false;
    for (std::size_t i = 0; i < n; ++i) {
      const auto& a = x[i];
      const auto& b = x[(i + 1) % n];
      const auto& c = x[(i + 2) % n];
      if (std::hypot(b[0] - a[0], b[1] - a[1]) > flowed_spacing) split[i] = any = true;
      if (turning_angle(a.data(), b.data(), c.data()) > max_turn)
        split[i] = split[(i + 1) % n] = any = true;
    }
    if (!any) break;
    if (n * 2 > max_samples) throw std::runtime_error("curve needs too many samples to resolve");
    std::vector<double> t2;
    std::vector<std::array<double, 2>> x2;
    t2.reserve(2 * n);
    x2.reserve(2 * n);
    for (std::size_t i = 0; i < n; ++i) {
      t2.push_back(theta[i]);
      x2.push_back(x[i]);
      if (split[i]) {
        const double t1 = i + 1 < n ? theta[i + 1] : two_pi;
        const double tm = 0.5 * (theta[i] + t1);
        t2.push_back(tm);
        x2.push_back(circle_image(phi, tm, false));
      }
    }
    theta.swap(t2);
    x.swap(x2);
  }
  double lo[2] = {1e300, 1e300}, hi[2] = {-1e300, -1e300};
  for (const auto& p : x)
    for (int a = 0; a < 2; ++a) {
      lo[a] = std::min(lo[a], p[a]);
      hi[a] = std::max(hi[a], p[a]);
    }
  phi.normalise_box(lo, hi);
  CurveSamples out;
  out.theta = std::move(theta);
  out.xy.resize(2 * out.theta.size());
  for (std::size_t i = 0; i < out.theta.size(); ++i) {
    const auto p = circle_image(phi, out.theta[i], true);
    out.xy[2 * i] = p[0];
    out.xy[2 * i + 1] = p[1];
  }
  return out;
}

std::vector<double> circle_crossings(const RandomDeformation& phi, const CurveSamples& curve,
                                     std::span<const double> center, double radius) {
  const std::size_t n = curve.size();
  auto level = [&](const double* p) {
    return std::hypot(p[0] - center[0], p[1] - center[1]) - radius;
  };
  std::vector<double> out;
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t j = (i + 1) % n;
    double fa = level(&curve.xy[2 * i]), fb = level(&curve.xy[2 * j]);
    if (fa == 0.0) {
      out.push_back(curve.theta[i]);
      continue;
    }
    if ((fa < 0.0) == (fb < 0.0) || fb == 0.0) continue;
    double ta = curve.theta[i], tb = j ? curve.theta[j] : two_pi;
    for (int it = 0; it < 200 && tb - ta > 1e-15; ++it) {
      const double tm = 0.5 * (ta + tb);
      if (tm <= ta || tm >= tb) break;
      const auto p = circle_image(phi, tm, true);
      const double fm = level(p.data());
      if (fm == 0.0) {
        ta = tb = tm;
        break;
      }
      if ((fm < 0.0) == (fa < 0.0)) {
        ta = tm;
        fa = fm;
      } else {
        tb = tm;
      }
    }
    // Keep the end whose image is closer to the circle.
    const auto pa = circle_image(phi, ta, true), pb = circle_image(phi, tb, true);
    double t = std::abs(level(pa.data())) <= std::abs(level(pb.data())) ? ta : tb;
    if (t >= two_pi) t -= two_pi;
    out.push_back(t);
  }
  std::sort(out.begin(), out.end());
  return out;
}

namespace {

/// A candidate vertex of the resolved curve: its parameter, position, the local size of the
/// nearest sample, and whether it must be kept (a forced parameter).
struct CurveCandidate {
  double theta;
  double x, y, size;
  bool keep;
};

/// Candidate vertices in parameter order: the samples and the forced parameters (a sample that
/// coincides with a forced point is dropped in favour of the forced one).
std::vector<CurveCandidate> curve_candidates(const RandomDeformation& phi, const CurveSamples& curve,
                                             std::span<const double> local_size, std::span<const double> forced) {
  const std::size_t n = curve.size();
  std::vector<CurveCandidate> cand;
  cand.reserve(n + forced.size());
  std::vector<double> f(forced.begin(), forced.end());
  std::sort(f.begin(), f.end());
  std::size_t k = 0;
  for (std::size_t i = 0; i < n; ++i) {
    while (k < f.size() && f[k] <= curve.theta[i]) {
      const auto p = circle_image(phi, f[k], true);
      const double s = std::min(local_size[i], local_size[(i + n - 1) % n]);
      if (!cand.empty() && cand.back().theta == f[k]) cand.pop_back();
      cand.push_back({f[k], p[0], p[1], s, true});
      ++k;
    }
    if (!cand.empty() && cand.back().theta == curve.theta[i]) continue;
    cand.push_back({curve.theta[i], curve.xy[2 * i], curve.xy[2 * i + 1], local_size[i], false});
  }
  for (; k < f.size(); ++k) {
    const auto p = circle_image(phi, f[k], true);
    cand.push_back({f[k], p[0], p[1], std::min(local_size[n - 1], local_size[0]), true});
  }
  return cand;
}

}  // namespace

Boundary resolve_curve(const RandomDeformation& phi, const CurveSamples& curve,
                       std::span<const double> local_size, std::span<const double> forced) {
  assert(local_size.size() == curve.size());
  const std::vector<CurveCandidate> cand = curve_candidates(phi, curve, local_size, forced);
  const std::size_t m = cand.size();
  // Start at a kept candidate if there is one, so the walk never skips it.
  std::size_t start = 0;
  for (std::size_t i = 0; i < m; ++i)
    if (cand[i].keep) {
      start = i;
      break;
    }
  std::vector<double> xy;
  std::size_t cur = start;
  std::size_t steps = 0;
  do {
    xy.push_back(cand[cur].x);
    xy.push_back(cand[cur].y);
    // Advance as far as possible: the chord from cur to the next vertex must not exceed the
    // smallest size over the candidates in between, and kept candidates stop the walk.
    std::size_t next = (cur + 1) % m;
    double smin = cand[cur].size;
    for (std::size_t step = 1; step < m; ++step) {
      const std::size_t j = (cur + step) % m;
      smin = std::min(smin, cand[j].size);
      const double chord = std::hypot(cand[j].x - cand[cur].x, cand[j].y - cand[cur].y);
      if (chord > smin && step > 1) break;
      next = j;
      if (cand[j].keep || j == start) break;
    }
    cur = next;
    if (++steps > m) throw std::logic_error("resolve_curve: walk did not close");
  } while (cur != start);
  return polygon_boundary(std::move(xy));
}

std::vector<double> curvature_radii(const CurveSamples& curve, double arm) {
  const std::size_t n = curve.size();
  std::vector<double> r(n, std::numeric_limits<double>::infinity());
  std::vector<double> seg(n);  // seg[i]: length of the chord from sample i to i + 1
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t j = (i + 1) % n;
    seg[i] = std::hypot(curve.xy[2 * j] - curve.xy[2 * i], curve.xy[2 * j + 1] - curve.xy[2 * i + 1]);
  }
  for (std::size_t i = 0; i < n; ++i) {
    // The samples about `arm` of arc length before and after sample i.
    std::size_t f = i, b = i;
    double df = 0.0, db = 0.0;
    for (std::size_t k = 0; k + 2 < n && df < arm; ++k) df += seg[f], f = (f + 1) % n;
    for (std::size_t k = 0; k + 2 < n && db < arm; ++k) b = (b + n - 1) % n, db += seg[b];
    const double* pa = &curve.xy[2 * b];
    const double* pb = &curve.xy[2 * i];
    const double* pc = &curve.xy[2 * f];
    const double ab = std::hypot(pb[0] - pa[0], pb[1] - pa[1]);
    const double bc = std::hypot(pc[0] - pb[0], pc[1] - pb[1]);
    const double ca = std::hypot(pa[0] - pc[0], pa[1] - pc[1]);
    const double cross =
        std::abs((pb[0] - pa[0]) * (pc[1] - pa[1]) - (pb[1] - pa[1]) * (pc[0] - pa[0]));
    if (cross > 0.0) r[i] = ab * bc * ca / (2.0 * cross);
  }
  return r;
}

void grade_sizes(const CurveSamples& curve, std::vector<double>& size, double grading) {
  const std::size_t n = curve.size();
  std::vector<double> seg(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t j = (i + 1) % n;
    seg[i] = std::hypot(curve.xy[2 * j] - curve.xy[2 * i], curve.xy[2 * j + 1] - curve.xy[2 * i + 1]);
  }
  // Two sweeps in each direction around the loop settle the periodic minimum.
  for (int sweep = 0; sweep < 2; ++sweep) {
    for (std::size_t k = 1; k <= n; ++k) {
      const std::size_t i = k % n, p = k - 1;
      size[i] = std::min(size[i], size[p] + grading * seg[p]);
    }
    for (std::size_t k = n; k-- > 0;) {
      const std::size_t i = k, q = (k + 1) % n;
      size[i] = std::min(size[i], size[q] + grading * seg[i]);
    }
  }
}

// ---- 3D -----------------------------------------------------------------------------------

namespace {

std::uint64_t edge_key(int a, int b) {
  if (a > b) std::swap(a, b);
  return (std::uint64_t(std::uint32_t(a)) << 32) | std::uint32_t(b);
}

}  // namespace

namespace {

/// Longest-edge propagation path bisection (Rivara) of a closed triangle surface, driven by its
/// image under a flow: every triangle whose image edges are longer than the spacing is refined.
/// A triangle is refined by bisecting the terminal edge of its LEPP, the first edge on the path
/// that is the longest edge of both of its triangles, until it is resolved. Bisecting only
/// longest pre-image edges keeps the pre-image triangles shape-regular (angles bounded below by
/// half the smallest angle of the base), so their diameters shrink geometrically and the
/// refinement ends wherever phi is continuous. (Bisecting the longest IMAGE edge instead does not
/// end where the image folds back on itself closer than `spacing`: the points then pile up on a
/// pre-image edge whose image is short.)
class LeppRefiner {
 public:
  LeppRefiner(RandomDeformation& phi, const Boundary& base, BaseKind kind, double flowed_spacing,
              std::int64_t max_points)
      : phi_(phi), kind_(kind), limit2_(flowed_spacing * flowed_spacing), max_points_(max_points),
        pre_(base.points.begin(), base.points.end()), img_(pre_), tri_(base.facets.begin(), base.facets.end()) {
    for (std::size_t i = 0; i < img_.size(); i += 3) phi_.flow(&img_[i]);
    edge_tris_.reserve(2 * tri_.size());
    const int n_tri0 = int(tri_.size() / 3);
    for (int t = 0; t < n_tri0; ++t)
      for (int q = 0; q < 3; ++q) add_edge_tri(tri_[3 * t + q], tri_[3 * t + (q + 1) % 3], t);
    for (const auto& [key, tris] : edge_tris_)
      if (tris[1] < 0) throw std::runtime_error("base surface is not closed");
    for (int t = 0; t < n_tri0; ++t)
      if (unresolved(t)) queue_.push_back(t);
  }

  /// Refines until every triangle is resolved (first in, first out).
  void refine() {
    for (std::size_t head = 0; head < queue_.size(); ++head)
      while (unresolved(queue_[head])) bisect_terminal_edge(queue_[head]);
  }

  std::vector<double>& preimage() { return pre_; }
  const std::vector<double>& image() const { return img_; }
  std::vector<int>& triangles() { return tri_; }

 private:
  void add_edge_tri(int a, int b, int t) {
    auto [it, inserted] = edge_tris_.try_emplace(edge_key(a, b), std::array<int, 2>{t, -1});
    if (inserted) return;
    if (it->second[1] >= 0) throw std::runtime_error("base surface is not a 2-manifold");
    it->second[1] = t;
  }
  void replace_edge_tri(int a, int b, int old_t, int new_t) {
    auto& e = edge_tris_.at(edge_key(a, b));
    (e[0] == old_t ? e[0] : e[1]) = new_t;
  }
  static double dist2(const std::vector<double>& x, int a, int b) {
    const double* p = &x[3 * std::size_t(a)];
    const double* q = &x[3 * std::size_t(b)];
    return (p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]);
  }
  /// A triangle is resolved when its image edges are no longer than the spacing.
  bool unresolved(int t) const {
    const int* v = &tri_[3 * std::size_t(t)];
    return dist2(img_, v[0], v[1]) > limit2_ || dist2(img_, v[1], v[2]) > limit2_ || dist2(img_, v[2], v[0]) > limit2_;
  }
  /// The longest edge of a triangle in the PRE-IMAGE (ties broken by vertex ids, so that "the
  /// longest edge" is a strict total order): the position q of edge (v[q], v[q+1]).
  int longest(int t) const {
    const int* v = &tri_[3 * std::size_t(t)];
    int best = 0;
    double best_len = -1.0;
    std::uint64_t best_key = 0;
    for (int q = 0; q < 3; ++q) {
      const double l = dist2(pre_, v[q], v[(q + 1) % 3]);
      const std::uint64_t k = edge_key(v[q], v[(q + 1) % 3]);
      if (l > best_len || (l == best_len && k > best_key)) best = q, best_len = l, best_key = k;
    }
    return best;
  }
  /// Position of the directed edge a->b inside triangle t, or -1.
  int directed(int t, int a, int b) const {
    for (int q = 0; q < 3; ++q)
      if (tri_[3 * t + q] == a && tri_[3 * t + (q + 1) % 3] == b) return q;
    return -1;
  }
  /// Walks the longest-edge path from t and bisects its terminal edge.
  void bisect_terminal_edge(int t) {
    for (int cur = t;;) {
      const int q = longest(cur);
      const int a = tri_[3 * cur + q], b = tri_[3 * cur + (q + 1) % 3];
      const auto& tris = edge_tris_.at(edge_key(a, b));
      const int other = tris[0] == cur ? tris[1] : tris[0];
      const int qo = longest(other);
      if (edge_key(tri_[3 * other + qo], tri_[3 * other + (qo + 1) % 3]) == edge_key(a, b)) return bisect(a, b);
      cur = other;
    }
  }
  /// The midpoint of the pre-image edge (a, b), projected per `kind`, appended with its image.
  int add_midpoint(int a, int b) {
    if (std::int64_t(pre_.size() / 3) >= max_points_)
      throw std::runtime_error("surface needs too many points to resolve (more than " + std::to_string(max_points_) +
                               ")");
    double p[3];
    for (int k = 0; k < 3; ++k) p[k] = 0.5 * (pre_[3 * std::size_t(a) + k] + pre_[3 * std::size_t(b) + k]);
    if (kind_ == BaseKind::sphere) {
      const double r = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
      for (double& v : p) v /= r;
    }
    pre_.insert(pre_.end(), p, p + 3);
    phi_.flow(p);
    img_.insert(img_.end(), p, p + 3);
    return int(pre_.size() / 3) - 1;
  }
  /// Splits edge (a, b) at its midpoint and both of its triangles in two; queues the four.
  void bisect(int a, int b) {
    const auto tris = edge_tris_.at(edge_key(a, b));
    int t1 = tris[0], t2 = tris[1];
    if (directed(t1, a, b) < 0) std::swap(t1, t2);  // t1 holds a->b, t2 holds b->a
    const int q1 = directed(t1, a, b), q2 = directed(t2, b, a);
    if (q1 < 0 || q2 < 0) throw std::runtime_error("base surface is not consistently oriented");
    const int c = tri_[3 * t1 + (q1 + 2) % 3];
    const int d = tri_[3 * t2 + (q2 + 2) % 3];
    const int m = add_midpoint(a, b);
    // t1 = (a, b, c) -> (a, m, c) and new t3 = (m, b, c);
    // t2 = (b, a, d) -> (b, m, d) and new t4 = (m, a, d).
    const int t3 = int(tri_.size() / 3), t4 = t3 + 1;
    tri_[3 * t1 + 0] = a, tri_[3 * t1 + 1] = m, tri_[3 * t1 + 2] = c;
    tri_[3 * t2 + 0] = b, tri_[3 * t2 + 1] = m, tri_[3 * t2 + 2] = d;
    tri_.insert(tri_.end(), {m, b, c, m, a, d});
    edge_tris_.erase(edge_key(a, b));
    replace_edge_tri(b, c, t1, t3);
    replace_edge_tri(a, d, t2, t4);
    edge_tris_[edge_key(a, m)] = {t1, t4};
    edge_tris_[edge_key(m, b)] = {t3, t2};
    edge_tris_[edge_key(m, c)] = {t1, t3};
    edge_tris_[edge_key(m, d)] = {t2, t4};
    queue_.insert(queue_.end(), {t1, t2, t3, t4});
  }

  RandomDeformation& phi_;
  BaseKind kind_;
  double limit2_;
  std::int64_t max_points_;
  std::vector<double> pre_, img_;
  std::vector<int> tri_;
  std::unordered_map<std::uint64_t, std::array<int, 2>> edge_tris_;
  std::vector<int> queue_;  // triangles to look at, first in first out
};

}  // namespace

SurfaceSamples sample_surface_image(RandomDeformation& phi, const Boundary& base, BaseKind kind,
                                    double spacing, std::int64_t max_points) {
  assert(phi.dim() == 3 && base.dim == 3);
  LeppRefiner lepp(phi, base, kind, spacing / phi.scale(), max_points);
  lepp.refine();
  double lo[3], hi[3];
  bounding_box(3, lepp.image(), lo, hi);
  phi.normalise_box(lo, hi);
  SurfaceSamples out;
  out.surface.dim = 3;
  out.surface.facets = std::move(lepp.triangles());
  std::vector<double>& pre = lepp.preimage();
  out.surface.points.resize(pre.size());
  for (std::size_t i = 0; i < pre.size(); i += 3) {
    double x[3] = {pre[i], pre[i + 1], pre[i + 2]};
    phi.map(x);
    std::copy(x, x + 3, &out.surface.points[i]);
  }
  out.preimage = std::move(pre);
  return out;
}

Boundary icosphere(int level) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<double> p = {-1, t, 0, 1, t, 0, -1, -t, 0, 1, -t, 0, 0, -1, t, 0, 1, t,
                           0, -1, -t, 0, 1, -t, t, 0, -1, t, 0, 1, -t, 0, -1, -t, 0, 1};
  std::vector<int> f = {0, 11, 5, 0, 5,  1,  0,  1,  7,  0,  7,  10, 0, 10, 11,
                        1, 5,  9, 5, 11, 4,  11, 10, 2,  10, 7,  6,  7, 1,  8,
                        3, 9,  4, 3, 4,  2,  3,  2,  6,  3,  6,  8,  3, 8,  9,
                        4, 9,  5, 2, 4,  11, 6,  2,  10, 8,  6,  7,  9, 8,  1};
  auto normalise = [&](std::size_t i) {
    const double r = std::sqrt(p[i] * p[i] + p[i + 1] * p[i + 1] + p[i + 2] * p[i + 2]);
    p[i] /= r, p[i + 1] /= r, p[i + 2] /= r;
  };
  for (std::size_t i = 0; i < p.size(); i += 3) normalise(i);
  for (int l = 0; l < level; ++l) {
    std::unordered_map<std::uint64_t, int> mid;
    auto midpoint = [&](int a, int b) {
      auto [it, inserted] = mid.try_emplace(edge_key(a, b), int(p.size() / 3));
      if (inserted) {
        for (int k = 0; k < 3; ++k) p.push_back(0.5 * (p[3 * a + k] + p[3 * b + k]));
        normalise(p.size() - 3);
      }
      return it->second;
    };
    std::vector<int> g;
    g.reserve(4 * f.size());
    for (std::size_t i = 0; i < f.size(); i += 3) {
      const int a = f[i], b = f[i + 1], c = f[i + 2];
      const int ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
      g.insert(g.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
    }
    f.swap(g);
  }
  Boundary b;
  b.dim = 3;
  b.points = std::move(p);
  b.facets = std::move(f);
  return b;
}

Boundary unit_circle(int n) {
  std::vector<double> xy(2 * std::size_t(n));
  for (int i = 0; i < n; ++i) {
    xy[2 * i] = std::cos(two_pi * i / n);
    xy[2 * i + 1] = std::sin(two_pi * i / n);
  }
  return polygon_boundary(std::move(xy));
}

}  // namespace hypershape::geometry
