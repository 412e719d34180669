#include "hypershape/factory/accuracy.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <numeric>
#include <stdexcept>

#include "hypershape/geometry/boundary.hpp"
#include "hypershape/mesh/boundary_mesher.hpp"
#include "hypershape/mesh/refine.hpp"

namespace hypershape::factory {

AccuracyLevel accuracy_level(const config::DatasetConfig& cfg, int level) {
  AccuracyLevel a;
  a.level = level;
  const int base = cfg.degree;
  a.degree = base == 1 && level == 0 ? 1 : 2;
  a.refinements = base == 1 ? std::max(0, level - 1) : level;
  a.h = std::max(cfg.shapes.h, cfg.shapes.mesh_h) / double(1 << a.refinements);
  return a;
}

double predicted_reduction(const AccuracyLevel& from, const AccuracyLevel& to) {
  const double degree = from.degree == 1 && to.degree == 2 ? 10.0 : 1.0;
  return degree * std::pow(2.0, to.refinements - from.refinements);
}

int next_accuracy_level(const config::DatasetConfig& cfg, int current, double worst) {
  const int last = cfg.accuracy.max_level;
  if (worst < 0) return std::min(current + 1, last);
  const AccuracyLevel from = accuracy_level(cfg, current);
  for (int k = current + 1; k < last; ++k)
    if (worst / predicted_reduction(from, accuracy_level(cfg, k)) <= cfg.accuracy.rel_l2) return k;
  return std::max(current + 1, last);
}

bool curable(const config::DatasetConfig& cfg, int current, double rel_l2) {
  const int last = cfg.accuracy.max_level;
  if (rel_l2 < 0 || current >= last) return rel_l2 < 0 && current < last;
  return rel_l2 / predicted_reduction(accuracy_level(cfg, current), accuracy_level(cfg, last)) <= cfg.accuracy.rel_l2;
}

LoadLadder::LoadLadder(const config::DatasetConfig& cfg, int n_loads)
    : cfg_(cfg), allowed_(std::size_t(std::floor(cfg.accuracy.exceed_share * double(n_loads) + 1e-9))),
      kept_(std::size_t(n_loads), 0), waiting_(std::size_t(n_loads), -1), tried_(std::size_t(n_loads), 0U),
      estimate_(std::size_t(n_loads), -1.0) {
  if (cfg.accuracy.max_level >= int(8 * sizeof(unsigned)))
    throw std::logic_error("LoadLadder: max_level beyond the tried-level mask");
}

bool LoadLadder::record(int L, int k, bool converged, double estimate) {
  const auto i = std::size_t(L);
  tried_[i] |= 1U << k;
  const double before = estimate_[i];
  const bool keep = k == 0 || (converged && estimate >= 0 && (before < 0 || estimate < before));
  if (keep) {
    kept_[i] = k;
    estimate_[i] = converged ? estimate : -1.0;
    waiting_[i] = converged ? climb(L, k, estimate_[i]) : -1;
    return true;
  }
  // Not kept: fall back to the highest level between the kept label's and k never tried; else,
  // if it converged, climb on from its own estimate.
  waiting_[i] = converged ? climb(L, k, estimate) : -1;
  for (int j = k - 1; j > kept_[i]; --j)
    if (!tried(L, j)) {
      waiting_[i] = j;
      break;
    }
  return false;
}

int LoadLadder::climb(int L, int from, double e) const {
  if (!exceeds(cfg_.accuracy, e) || !curable(cfg_, from, e)) return -1;
  // start: coarse: one level at a time, so that each re-solve can start from the state the last
  // label's estimate reached on its mesh refined (a jump starts from rest).
  const int first = cfg_.accuracy.start_from_coarse ? from + 1 : next_accuracy_level(cfg_, from, e);
  for (int k = first; k <= cfg_.accuracy.max_level; ++k)
    if (!tried(L, k)) return k;
  return -1;
}

int LoadLadder::next(std::vector<int>& loads) const {
  loads.clear();
  int lowest = -1;
  std::size_t waiting = 0;
  for (int w : waiting_)
    if (w >= 0) waiting += 1, lowest = lowest < 0 ? w : std::min(lowest, w);
  if (waiting <= allowed_) return -1;  // no more than the allowed share would climb
  for (std::size_t L = 0; L < waiting_.size(); ++L)
    if (waiting_[L] == lowest) loads.push_back(int(L));
  return lowest;
}

int LoadLadder::highest_tried(int L) const {
  int k = 0;
  for (unsigned m = tried_[std::size_t(L)] >> 1; m; m >>= 1) ++k;
  return k;
}

namespace {

/// The fine vertex at the midpoint of each coarse edge (a < b), read from the children's
/// barycentric coordinates (a midpoint has two entries of exactly 0.5).
std::map<std::pair<int, int>, int> midpoints(const mesh::RefinedMesh& r, int d) {
  const int nv = d + 1;
  std::map<std::pair<int, int>, int> mid;
  for (std::int64_t k = 0; k < r.mesh.n_cells(); ++k) {
    const auto parent = std::size_t(r.parent[std::size_t(k)]);
    for (int j = 0; j < nv; ++j) {
      const double* lam = &r.bary[(std::size_t(k) * std::size_t(nv) + std::size_t(j)) * std::size_t(nv)];
      int ends[2] = {-1, -1}, n = 0;
      for (int i = 0; i < nv; ++i)
        if (lam[i] == 0.5 && n < 2) ends[n++] = r.coarse_cells[parent * std::size_t(nv) + std::size_t(i)];
      if (n == 2) mid[std::minmax(ends[0], ends[1])] = r.mesh.cells[std::size_t(k) * std::size_t(nv) + std::size_t(j)];
    }
  }
  return mid;
}

/// Children of boundary facet (local corners; 3 = m01, 4 = m12, 5 = m20 in 3D, 2 = m01 in 2D), each
/// oriented as its parent.
const std::vector<std::array<int, 3>>& facet_children(int d) {
  static const std::vector<std::array<int, 3>> c2{{0, 2, 0}, {2, 1, 0}};
  static const std::vector<std::array<int, 3>> c3{{0, 3, 5}, {3, 1, 4}, {5, 4, 2}, {3, 4, 5}};
  return d == 2 ? c2 : c3;
}

}  // namespace

std::vector<std::int64_t> node_permutation(const std::vector<double>& from, const std::vector<double>& to, int dim) {
  const std::size_t d = std::size_t(dim), n = from.size() / d;
  if (from.size() != to.size() || n * d != from.size()) return {};
  auto sorted = [&](const std::vector<double>& x) {
    std::vector<std::int64_t> order(n);
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](std::int64_t a, std::int64_t b) {
      return std::lexicographical_compare(&x[std::size_t(a) * d], &x[std::size_t(a) * d] + d, &x[std::size_t(b) * d],
                                          &x[std::size_t(b) * d] + d);
    });
    return order;
  };
  const auto a = sorted(from), b = sorted(to);
  std::vector<std::int64_t> p(n);
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::equal(&from[std::size_t(a[i]) * d], &from[std::size_t(a[i]) * d] + d, &to[std::size_t(b[i]) * d]))
      return {};
    p[std::size_t(b[i])] = a[i];
  }
  return p;
}

ShapeSample refine_shape(const ShapeSample& shape) {
  const int d = shape.mesh.dim;
  const mesh::RefinedMesh r = mesh::refine_uniform(shape.mesh);
  const auto mid = midpoints(r, d);
  const geometry::Boundary& b = shape.boundary;
  // New numbering: the boundary's nodes first (in 2D along the polygon), then the rest in order.
  std::vector<int> renum(std::size_t(r.mesh.n_vertices()), -1);
  int next = 0;
  auto take = [&](int v) {
    if (renum[std::size_t(v)] < 0) renum[std::size_t(v)] = next++;
    return renum[std::size_t(v)];
  };
  std::vector<std::array<int, 6>> corners(std::size_t(b.n_facets()));  // fine ids: vertices, then midpoints
  for (std::int64_t f = 0; f < b.n_facets(); ++f) {
    const auto v = b.facet(f);
    auto& c = corners[std::size_t(f)];
    for (int i = 0; i < d; ++i) c[std::size_t(i)] = v[std::size_t(i)];
    for (int i = 0; i < (d == 2 ? 1 : 3); ++i) {
      const auto it = mid.find(std::minmax(v[std::size_t(i)], v[std::size_t((i + 1) % d)]));
      if (it == mid.end()) throw std::logic_error("refine_shape: a boundary facet is not an edge/face of the mesh");
      c[std::size_t(d + i)] = it->second;
    }
    if (d == 2) take(c[0]), take(c[2]), take(c[1]);
    else for (int i = 0; i < 6; ++i) take(c[std::size_t(i)]);
  }
  const int n_boundary = next;
  for (std::size_t v = 0; v < renum.size(); ++v) take(int(v));
  ShapeSample out = shape;
  out.mesh.dim = d;
  out.mesh.coords.assign(r.mesh.coords.size(), 0.0);
  for (std::size_t v = 0; v < renum.size(); ++v)
    for (int k = 0; k < d; ++k)
      out.mesh.coords[std::size_t(renum[v]) * std::size_t(d) + std::size_t(k)] = r.mesh.coords[v * std::size_t(d) + std::size_t(k)];
  out.mesh.cells.resize(r.mesh.cells.size());
  for (std::size_t i = 0; i < r.mesh.cells.size(); ++i) out.mesh.cells[i] = renum[std::size_t(r.mesh.cells[i])];
  out.boundary.dim = d;
  out.boundary.points.assign(out.mesh.coords.begin(), out.mesh.coords.begin() + std::ptrdiff_t(n_boundary * d));
  out.boundary.facets.clear();
  const auto& children = facet_children(d);
  for (const auto& c : corners)
    for (const auto& ch : children)
      for (int i = 0; i < d; ++i) out.boundary.facets.push_back(renum[std::size_t(c[std::size_t(ch[std::size_t(i)])])]);
  out.dirichlet_facets.clear();
  for (int f : shape.dirichlet_facets)
    for (std::size_t k = 0; k < children.size(); ++k) out.dirichlet_facets.push_back(f * int(children.size()) + int(k));
  return out;
}

AccuracySummary& AccuracySummary::operator+=(const AccuracySummary& o) {
  for (int k = 0; k < kLevels; ++k) shapes_at_level[std::size_t(k)] += o.shapes_at_level[std::size_t(k)];
  for (int k = 0; k < kLevels; ++k) loads_at_level[std::size_t(k)] += o.loads_at_level[std::size_t(k)];
  loads_meeting += o.loads_meeting, loads_exceeding += o.loads_exceeding, solved_again += o.solved_again;
  fell_back += o.fell_back;
  discarded_loads += o.discarded_loads, discarded_newton += o.discarded_newton;
  discarded_factorizations += o.discarded_factorizations;
  return *this;
}

void AccuracySummary::sum_over(MPI_Comm comm, bool contribute) {
  std::vector<std::int64_t*> all{&loads_meeting,   &loads_exceeding,  &solved_again,           &fell_back,
                                 &discarded_loads, &discarded_newton, &discarded_factorizations};
  for (auto& x : shapes_at_level) all.push_back(&x);
  for (auto& x : loads_at_level) all.push_back(&x);
  std::vector<std::int64_t> v(all.size()), t(all.size());
  for (std::size_t i = 0; i < all.size(); ++i) v[i] = contribute ? *all[i] : 0;
  MPI_Allreduce(v.data(), t.data(), int(v.size()), MPI_INT64_T, MPI_SUM, comm);
  for (std::size_t i = 0; i < all.size(); ++i) *all[i] = t[i];
}

std::int64_t AccuracySummary::shapes() const {
  std::int64_t n = 0;
  for (auto s : shapes_at_level) n += s;
  return n;
}

nlohmann::json AccuracySummary::json(const config::AccuracyConfig& a) const {
  const auto n = loads_meeting + loads_exceeding;
  return {{"rel_l2_bound", a.rel_l2},
          {"max_level", a.max_level},
          {"shapes_at_level", shapes_at_level},
          {"load_cases_at_level", loads_at_level},
          {"load_cases_meeting", loads_meeting},
          {"load_cases_exceeding", loads_exceeding},
          {"share_meeting", n ? double(loads_meeting) / double(n) : 0.0},
          {"load_cases_solved_again", solved_again},
          {"load_cases_fell_back", fell_back},
          {"discarded_load_cases", discarded_loads},
          {"discarded_newton_iterations", discarded_newton},
          {"discarded_numeric_factorizations", discarded_factorizations}};
}

std::string AccuracySummary::line(const config::AccuracyConfig& a) const {
  if (!a.enabled()) return "";
  const auto n = loads_meeting + loads_exceeding;
  std::string shapes, labels;
  for (int k = 0; k <= a.max_level && k < kLevels; ++k) {
    shapes += fmt::format("{}{}: {}", k ? ", " : "", k, shapes_at_level[std::size_t(k)]);
    labels += fmt::format("{}{}: {}", k ? ", " : "", k, loads_at_level[std::size_t(k)]);
  }
  return fmt::format("  accuracy rel_l2 <= {:g}: {} of {} converged load cases meet it ({:.1f}%); labels per level "
                     "{}; shapes stored per level {}; {} load cases solved again ({} at a level skipped), {} labels "
                     "not kept ({} Newton iterations, {} factorisations)\n",
                     a.rel_l2, loads_meeting, n, n ? 100.0 * double(loads_meeting) / double(n) : 0.0, labels, shapes,
                     solved_again, fell_back, discarded_loads, discarded_newton, discarded_factorizations);
}

}  // namespace hypershape::factory
