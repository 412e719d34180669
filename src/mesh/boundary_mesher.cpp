#include "hypershape/mesh/boundary_mesher.hpp"

#include <gmsh.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <utility>

#include "hypershape/core/vec3.hpp"
#include "hypershape/mesh/gmsh_mesher.hpp"
#include "hypershape/mesh/quality.hpp"
#include "gmsh_util.hpp"

namespace hypershape::mesh {

namespace {

using geometry::Boundary;

[[noreturn]] void bad_input(const std::string& what) {
  throw std::invalid_argument("mesh_boundary: " + what);
}

[[noreturn]] void mesh_failed(const std::string& what) {
  throw std::runtime_error("mesh_boundary: " + what);
}

// ---- input checks --------------------------------------------------------------------------

/// Checks what every dimension needs: indices in range, every point on a facet, no two points
/// at the same place (vertices are matched back to boundary points by their coordinates).
void check_common(const Boundary& b, const BoundaryMeshOptions& opt) {
  if (b.dim != 2 && b.dim != 3) bad_input("dimension must be 2 or 3, got " + std::to_string(b.dim));
  if (!(opt.h > 0) || !std::isfinite(opt.h)) bad_input("h must be positive and finite");
  if (!(opt.grading > 0) || !std::isfinite(opt.grading)) bad_input("grading must be positive");
  const std::int64_t n = b.n_points();
  if (b.points.size() != std::size_t(n) * b.dim || b.facets.size() % b.dim != 0)
    bad_input("points/facets sizes are not multiples of the dimension");
  if (n < b.dim + 1) bad_input("too few points (" + std::to_string(n) + ")");
  for (double x : b.points)
    if (!std::isfinite(x)) bad_input("a point coordinate is not finite");
  if (!opt.point_sizes.empty()) {
    if (std::int64_t(opt.point_sizes.size()) != n)
      bad_input("point_sizes has " + std::to_string(opt.point_sizes.size()) + " entries for " +
                std::to_string(n) + " points");
    for (double s : opt.point_sizes)
      if (!(s > 0) || !std::isfinite(s)) bad_input("point_sizes must be positive and finite");
  }
  std::vector<char> used(std::size_t(n), 0);
  for (int v : b.facets) {
    if (v < 0 || v >= n) bad_input("facet index " + std::to_string(v) + " out of range");
    used[std::size_t(v)] = 1;
  }
  if (std::count(used.begin(), used.end(), 0) > 0) bad_input("a point lies on no facet");
  std::map<std::array<double, 3>, std::int64_t> seen;
  for (std::int64_t i = 0; i < n; ++i) {
    std::array<double, 3> key{0, 0, 0};
    for (int k = 0; k < b.dim; ++k) key[k] = b.points[std::size_t(i * b.dim + k)];
    if (!seen.emplace(key, i).second)
      bad_input("points " + std::to_string(seen[key]) + " and " + std::to_string(i) + " coincide");
  }
}

/// The polygon's segments in loop order (one closed loop through every point).
std::vector<std::array<int, 2>> polygon_loop(const Boundary& b) {
  const int n = int(b.n_points());
  if (b.n_facets() != n) bad_input("a closed polygon has as many segments as points");
  std::vector<int> next(std::size_t(n), -1), n_in(std::size_t(n), 0);
  for (std::int64_t f = 0; f < b.n_facets(); ++f) {
    const auto s = b.facet(f);
    if (s[0] == s[1]) bad_input("degenerate segment " + std::to_string(f));
    if (next[s[0]] != -1) bad_input("point " + std::to_string(s[0]) + " starts two segments");
    next[s[0]] = s[1];
    ++n_in[s[1]];
  }
  std::vector<std::array<int, 2>> loop;
  int v = b.facet(0)[0];
  do {
    if (n_in[v] != 1)
      bad_input("point " + std::to_string(v) + " ends " + std::to_string(n_in[v]) + " segments");
    loop.push_back({v, next[v]});
    v = next[v];
  } while (v != b.facet(0)[0] && int(loop.size()) <= n);
  if (int(loop.size()) != n) bad_input("the segments form more than one loop");
  return loop;
}

/// Every undirected edge of the surface is shared by exactly two triangles, in opposite
/// directions (closed, oriented 2-manifold).
void check_closed_surface(const Boundary& b) {
  std::map<std::pair<int, int>, int> directed;
  for (std::int64_t f = 0; f < b.n_facets(); ++f) {
    const auto t = b.facet(f);
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2])
      bad_input("degenerate triangle " + std::to_string(f));
    for (int k = 0; k < 3; ++k)
      if (++directed[{t[k], t[(k + 1) % 3]}] > 1)
        bad_input("edge (" + std::to_string(t[k]) + ", " + std::to_string(t[(k + 1) % 3]) +
                  ") is used twice in the same direction");
  }
  for (const auto& [e, count] : directed)
    if (!directed.contains({e.second, e.first}))
      bad_input("edge (" + std::to_string(e.first) + ", " + std::to_string(e.second) +
                ") has only one triangle: the surface is not closed");
}

// ---- sizes ---------------------------------------------------------------------------------

double distance(const double* a, const double* b, int dim) {
  double s = 0;
  for (int k = 0; k < dim; ++k) s += (a[k] - b[k]) * (a[k] - b[k]);
  return std::sqrt(s);
}

/// The edge length wanted at each boundary point: the mean length of its boundary edges, or the
/// point size where that is smaller. Not capped at h: next to the boundary the elements must
/// match the boundary edges as they are (gmsh leaves a polygon whose edges are several times
/// its size field almost empty, with no error).
std::vector<double> boundary_sizes(const Boundary& b, const BoundaryMeshOptions& opt) {
  const std::size_t n = std::size_t(b.n_points());
  std::vector<double> sum(n, 0.0), count(n, 0.0);
  for (std::int64_t f = 0; f < b.n_facets(); ++f) {
    const auto v = b.facet(f);
    // Segments: the one edge; triangles: each edge (seen twice over the closed surface, as each
    // point is, so the mean is unaffected).
    const int n_edges = b.dim == 2 ? 1 : 3;
    for (int k = 0; k < n_edges; ++k) {
      const int p = v[k], q = v[(k + 1) % b.dim];
      const double l =
          distance(&b.points[std::size_t(p) * b.dim], &b.points[std::size_t(q) * b.dim], b.dim);
      sum[p] += l, count[p] += 1;
      sum[q] += l, count[q] += 1;
    }
  }
  std::vector<double> s(n);
  for (std::size_t i = 0; i < n; ++i) {
    s[i] = sum[i] / count[i];
    if (!opt.point_sizes.empty()) s[i] = std::min(s[i], opt.point_sizes[i]);
  }
  return s;
}

/// gmsh's 3D Delaunay makes edges about 1.36 times its size field (mean interior edge / size
/// 1.34-1.37 on spheres and bumped spheres, h 0.06-0.15); its 2D Frontal-Delaunay makes edges
/// of the size (mean 0.99-1.0). Sizes given to gmsh are divided by this, so that h and the point
/// sizes are edge lengths in both dimensions.
double edge_per_gmsh_size(int dim) { return dim == 3 ? 1.4 : 1.0; }

/// The wanted edge length at x, moving linearly (rate g) from the boundary sizes s_i towards h:
///   min( min over s_i <= h of s_i + g |x - p_i|,  max(h, max over s_i > h of s_i - g |x - p_i|) ).
/// Boundary points finer than h pull the size down around them, coarser ones push it up (the
/// smaller wins where they meet); far from the boundary it is h. Returned in gmsh's size units
/// (times `scale`). Points are bucketed on a uniform grid; a query visits rings of cells
/// outwards until no farther point can change the result.
class GradedSize {
 public:
  GradedSize(int dim, const std::vector<double>& points, std::vector<double> sizes, double h,
             double grading, double scale)
      : dim_(dim), h_(h), g_(grading), scale_(scale), points_(points), sizes_(std::move(sizes)) {
    const std::size_t n = sizes_.size();
    s_min_ = *std::min_element(sizes_.begin(), sizes_.end());
    s_max_ = *std::max_element(sizes_.begin(), sizes_.end());
    coarse_reach_ = std::max(0.0, (s_max_ - h_) / g_);
    double extent = 0;
    for (int k = 0; k < dim_; ++k) {
      lo_[k] = std::numeric_limits<double>::max();
      hi_[k] = std::numeric_limits<double>::lowest();
      for (std::size_t i = 0; i < n; ++i) {
        lo_[k] = std::min(lo_[k], points_[i * dim_ + k]);
        hi_[k] = std::max(hi_[k], points_[i * dim_ + k]);
      }
      extent = std::max(extent, hi_[k] - lo_[k]);
    }
    // Half the reach of a fine point per cell, but not more cells than useful.
    const int max_cells_per_axis = dim_ == 2 ? 512 : 96;
    cell_ = std::max({0.5 * h_ / g_, extent / max_cells_per_axis, 1e-300});
    std::size_t n_cells = 1;
    for (int k = 0; k < 3; ++k) {
      n_[k] = k < dim_ ? std::max(1, int(std::ceil((hi_[k] - lo_[k]) / cell_))) : 1;
      n_cells *= std::size_t(n_[k]);
    }
    start_.assign(n_cells + 1, 0);
    std::vector<std::size_t> cell_of(n);
    for (std::size_t i = 0; i < n; ++i) {
      cell_of[i] = cell_index(&points_[i * dim_]);
      ++start_[cell_of[i] + 1];
    }
    for (std::size_t c = 0; c < n_cells; ++c) start_[c + 1] += start_[c];
    order_.resize(n);
    std::vector<std::size_t> fill(start_.begin(), start_.end() - 1);
    for (std::size_t i = 0; i < n; ++i) order_[fill[cell_of[i]]++] = int(i);
  }

  double operator()(double x, double y, double z) const {
    const double q[3] = {x, y, z};
    // Clamping to the points' box only brings q closer to every point: bounds stay valid.
    int ci[3] = {0, 0, 0};
    for (int k = 0; k < dim_; ++k) {
      const double qc = std::clamp(q[k], lo_[k], hi_[k]);
      ci[k] = std::min(n_[k] - 1, int((qc - lo_[k]) / cell_));
    }
    double fine = std::numeric_limits<double>::max();  // min over s_i <= h of s_i + g d
    double coarse = h_;                                // max(h, max over s_i > h of s_i - g d)
    const int max_ring = std::max({n_[0], n_[1], n_[2]});
    for (int r = 0; r <= max_ring; ++r) {
      const double d_lower = cell_ * std::max(0, r - 1);  // no point of ring r is closer
      const bool fine_done = s_min_ + g_ * d_lower >= std::min({fine, coarse, s_max_});
      if (fine_done && d_lower > coarse_reach_) break;
      const int rz = dim_ == 3 ? r : 0;
      for (int a = ci[0] - r; a <= ci[0] + r; ++a) {
        if (a < 0 || a >= n_[0]) continue;
        for (int b = ci[1] - r; b <= ci[1] + r; ++b) {
          if (b < 0 || b >= n_[1]) continue;
          for (int c = ci[2] - rz; c <= ci[2] + rz; ++c) {
            if (c < 0 || c >= n_[2]) continue;
            if (std::max({std::abs(a - ci[0]), std::abs(b - ci[1]), std::abs(c - ci[2])}) != r)
              continue;  // inside the ring: visited before
            const std::size_t cell = (std::size_t(a) * n_[1] + b) * n_[2] + c;
            for (std::size_t j = start_[cell]; j < start_[cell + 1]; ++j) {
              const int i = order_[j];
              const double d = distance(q, &points_[std::size_t(i) * dim_], dim_);
              if (sizes_[i] <= h_)
                fine = std::min(fine, sizes_[i] + g_ * d);
              else
                coarse = std::max(coarse, sizes_[i] - g_ * d);
            }
          }
        }
      }
    }
    return std::min(fine, coarse) * scale_;
  }

 private:
  std::size_t cell_index(const double* p) const {
    int c[3] = {0, 0, 0};
    for (int k = 0; k < dim_; ++k) c[k] = std::min(n_[k] - 1, int((p[k] - lo_[k]) / cell_));
    return (std::size_t(c[0]) * n_[1] + c[1]) * n_[2] + c[2];
  }

  int dim_;
  double h_, g_, scale_, s_min_ = 0, s_max_ = 0, coarse_reach_ = 0, cell_ = 1;
  double lo_[3] = {0, 0, 0}, hi_[3] = {0, 0, 0};
  int n_[3] = {1, 1, 1};
  const std::vector<double>& points_;
  std::vector<double> sizes_;
  std::vector<std::size_t> start_;
  std::vector<int> order_;
};

// ---- gmsh state ----------------------------------------------------------------------------

using detail::ScopedModel;

/// Sets gmsh options for one call and restores the previous values on exit: gmsh options are
/// process-global, and the other meshers do not set everything we change (e.g. smoothing).
class ScopedOptions {
 public:
  ScopedOptions() = default;
  ScopedOptions(const ScopedOptions&) = delete;
  ScopedOptions& operator=(const ScopedOptions&) = delete;
  ~ScopedOptions() {
    for (auto it = saved_.rbegin(); it != saved_.rend(); ++it) {
      try {
        gmsh::option::setNumber(it->first, it->second);
      } catch (...) {
      }
    }
  }
  void set(const std::string& name, double value) {
    double old = 0;
    gmsh::option::getNumber(name, old);
    saved_.emplace_back(name, old);
    gmsh::option::setNumber(name, value);
  }

 private:
  std::vector<std::pair<std::string, double>> saved_;
};

/// Installs the size callback for one call (it is process-global too).
class ScopedSizeCallback {
 public:
  explicit ScopedSizeCallback(const GradedSize& size) {
    gmsh::model::mesh::setSizeCallback(
        [&size](int, int, double x, double y, double z) { return size(x, y, z); });
  }
  ScopedSizeCallback(const ScopedSizeCallback&) = delete;
  ScopedSizeCallback& operator=(const ScopedSizeCallback&) = delete;
  ~ScopedSizeCallback() {
    try {
      gmsh::model::mesh::removeSizeCallback();
    } catch (...) {
    }
  }
};

void set_options(ScopedOptions& o, const Boundary& b, const BoundaryMeshOptions& opt) {
  o.set("General.Terminal", 0);
  o.set("General.NumThreads", 1);  // determinism
  // Log errors instead of throwing them: gmsh 4.8 throws from inside OpenMP regions (2D
  // meshing of a face), which terminates the process. With 1, meshing stops after an error;
  // mesh_boundary reads the errors from gmsh's logger.
  o.set("General.AbortOnError", 1);
  o.set("Mesh.ElementOrder", 1);
  // The size field can exceed h next to a boundary coarser than h; nothing else can.
  o.set("Mesh.MeshSizeMax", 1e22);  // gmsh's default
  o.set("Mesh.MeshSizeMin", 0.0);
  o.set("Mesh.MeshSizeFactor", 1.0);
  // The size comes only from the callback (GradedSize).
  o.set("Mesh.MeshSizeFromPoints", 0);
  o.set("Mesh.MeshSizeFromCurvature", 0);
  o.set("Mesh.MeshSizeExtendFromBoundary", 0);
  if (b.dim == 2) {
    // Frontal-Delaunay: on the test polygons it gave min angles 28-39 deg and edges within
    // 1.25-1.4 h; Delaunay (5) was ~1.5x faster with min angles 28-34 deg, edges up to 1.5 h.
    o.set("Mesh.Algorithm", 6);
    o.set("Mesh.Smoothing", opt.optimize ? 1 : 0);
  } else {
    // Classic Delaunay: HXT gave a different mesh on each call (gmsh_mesher.cpp).
    o.set("Mesh.Algorithm3D", 1);
    o.set("Mesh.Optimize", opt.optimize ? 1 : 0);
    // Optimise every tetrahedron of gamma quality below 0.6 (default 0.3): the smallest dihedral
    // angle rose from 12-14 to 18-21 deg on icospheres (h 0.06-0.12) for about 20% more time.
    o.set("Mesh.OptimizeThreshold", 0.6);
    o.set("Mesh.OptimizeNetgen", 0);  // not compiled into Debian's gmsh
  }
}

// ---- output --------------------------------------------------------------------------------

/// Signed measure, > 0 for a positively oriented cell in gmsh's convention (counter-clockwise
/// triangle, positive triple product). TODO(unify): same as signed_measure in gmsh_mesher.cpp.
double signed_measure(int dim, const std::vector<double>& x, const int* c) {
  const double* x0 = &x[std::size_t(c[0]) * dim];
  const double* x1 = &x[std::size_t(c[1]) * dim];
  const double* x2 = &x[std::size_t(c[2]) * dim];
  if (dim == 2) return (x1[0] - x0[0]) * (x2[1] - x0[1]) - (x1[1] - x0[1]) * (x2[0] - x0[0]);
  const double* x3 = &x[std::size_t(c[3]) * dim];
  const double a[3] = {x1[0] - x0[0], x1[1] - x0[1], x1[2] - x0[2]};
  const double e[3] = {x2[0] - x0[0], x2[1] - x0[1], x2[2] - x0[2]};
  const double d[3] = {x3[0] - x0[0], x3[1] - x0[1], x3[2] - x0[2]};
  return a[0] * (e[1] * d[2] - e[2] * d[1]) - a[1] * (e[0] * d[2] - e[2] * d[0]) +
         a[2] * (e[0] * d[1] - e[1] * d[0]);
}

/// The facets (sorted vertex indices) that belong to exactly one cell, sorted.
std::vector<std::array<int, 3>> boundary_facets(const MeshData& m) {
  const int nv = m.dim + 1;
  std::vector<std::array<int, 3>> faces;
  faces.reserve(std::size_t(m.n_cells()) * nv);
  for (std::int64_t c = 0; c < m.n_cells(); ++c) {
    const int* cell = &m.cells[std::size_t(c) * nv];
    for (int skip = 0; skip < nv; ++skip) {
      std::array<int, 3> f{-1, -1, -1};
      int k = 0;
      for (int a = 0; a < nv; ++a)
        if (a != skip) f[k++] = cell[a];
      std::sort(f.begin(), f.begin() + m.dim);
      faces.push_back(f);
    }
  }
  std::sort(faces.begin(), faces.end());
  std::vector<std::array<int, 3>> once;
  for (std::size_t i = 0; i < faces.size();) {
    std::size_t j = i;
    while (j < faces.size() && faces[j] == faces[i]) ++j;
    if (j - i == 1) once.push_back(faces[i]);
    i = j;
  }
  return once;
}

/// The gmsh nodes of the current model (xyz: 3 per node) mapped to output indices: a boundary
/// point of b (matched by its exact coordinates) or -1 - its position in node_tags (interior).
std::unordered_map<std::size_t, int> node_index(const Boundary& b, const std::vector<std::size_t>& node_tags,
                                                const std::vector<double>& xyz) {
  const int dim = b.dim;
  const std::int64_t n_bnd = b.n_points();
  std::map<std::array<double, 3>, int> boundary_index;
  for (std::int64_t i = 0; i < n_bnd; ++i) {
    std::array<double, 3> key{0, 0, 0};
    for (int k = 0; k < dim; ++k) key[k] = b.points[std::size_t(i * dim + k)];
    boundary_index.emplace(key, int(i));
  }
  std::unordered_map<std::size_t, int> index;
  index.reserve(node_tags.size());
  std::vector<char> matched(std::size_t(n_bnd), 0);
  for (std::size_t i = 0; i < node_tags.size(); ++i) {
    std::array<double, 3> key{0, 0, 0};
    for (int k = 0; k < dim; ++k) key[k] = xyz[3 * i + k];
    if (dim == 2 && xyz[3 * i + 2] != 0.0) mesh_failed("gmsh made a node off the plane");
    auto it = boundary_index.find(key);
    if (it != boundary_index.end()) {
      if (matched[it->second]++) mesh_failed("gmsh duplicated a boundary node");
      index[node_tags[i]] = it->second;
    } else {
      index[node_tags[i]] = -1 - int(i);
    }
  }
  if (std::count(matched.begin(), matched.end(), 0) > 0)
    mesh_failed("a boundary point is not a node of the mesh");
  return index;
}

/// Reads the simplices of the current model into MeshData: boundary points first (matched by
/// their exact coordinates, written from the input), then the interior vertices in order of
/// first use; cells oriented for PETSc.
MeshData collect(const Boundary& b) {
  const int dim = b.dim, nv = dim + 1;
  std::vector<std::size_t> node_tags;
  std::vector<double> xyz, param;
  gmsh::model::mesh::getNodes(node_tags, xyz, param, -1, -1, false, false);
  const std::unordered_map<std::size_t, int> index = node_index(b, node_tags, xyz);

  std::vector<std::size_t> elem_tags, elem_nodes;
  gmsh::model::mesh::getElementsByType(dim == 2 ? 2 : 4, elem_tags, elem_nodes, -1);
  if (elem_nodes.empty())
    mesh_failed(dim == 2 ? "gmsh made no triangles" : "gmsh made no tetrahedra");

  MeshData m;
  m.dim = dim;
  m.coords = b.points;
  m.cells.resize(elem_nodes.size());
  std::vector<int> interior(node_tags.size(), -1);
  for (std::size_t i = 0; i < elem_nodes.size(); ++i) {
    const auto it = index.find(elem_nodes[i]);
    if (it == index.end()) mesh_failed("an element references an unknown node");
    int v = it->second;
    if (v < 0) {
      const std::size_t pos = std::size_t(-1 - v);
      if (interior[pos] < 0) {
        interior[pos] = int(m.coords.size() / dim);
        for (int k = 0; k < dim; ++k) m.coords.push_back(xyz[3 * pos + k]);
      }
      v = interior[pos];
    }
    m.cells[i] = v;
  }
  for (std::int64_t c = 0; c < m.n_cells(); ++c) {
    int* cell = &m.cells[std::size_t(c) * nv];
    const double s = signed_measure(dim, m.coords, cell);
    // PETSc: triangles counter-clockwise, tetrahedra with negative triple product.
    if (dim == 2 ? s < 0 : s > 0) std::swap(cell[1], cell[2]);
  }
  return m;
}

/// Throws unless the facets of `m` that belong to one cell are exactly the input's.
void check_boundary(const Boundary& b, const MeshData& m) {
  const int dim = b.dim;
  std::vector<std::array<int, 3>> expected;
  expected.reserve(std::size_t(b.n_facets()));
  for (std::int64_t f = 0; f < b.n_facets(); ++f) {
    std::array<int, 3> key{-1, -1, -1};
    for (int k = 0; k < dim; ++k) key[k] = b.facet(f)[k];
    std::sort(key.begin(), key.begin() + dim);
    expected.push_back(key);
  }
  std::sort(expected.begin(), expected.end());
  const auto got = boundary_facets(m);
  if (got != expected)
    mesh_failed("the mesh boundary differs from the input (" + std::to_string(got.size()) +
                " boundary facets for " + std::to_string(expected.size()) + " input facets)");
}

// ---- the two dimensions --------------------------------------------------------------------

/// Geo points and one straight line per segment, each line meshed as exactly one edge.
void build_polygon(const Boundary& b) {
  const auto loop = polygon_loop(b);
  std::vector<int> point_tag(std::size_t(b.n_points()));
  for (std::int64_t i = 0; i < b.n_points(); ++i)  // sizes come from the callback, not points
    point_tag[i] = gmsh::model::geo::addPoint(b.points[2 * i], b.points[2 * i + 1], 0.0);
  std::vector<int> lines;
  lines.reserve(loop.size());
  for (const auto& [p, q] : loop) {
    lines.push_back(gmsh::model::geo::addLine(point_tag[p], point_tag[q]));
    gmsh::model::geo::mesh::setTransfiniteCurve(lines.back(), 2);
  }
  const int curve_loop = gmsh::model::geo::addCurveLoop(lines);
  gmsh::model::geo::addPlaneSurface({curve_loop});
  gmsh::model::geo::synchronize();
}

/// The surface as a discrete entity holding exactly the input triangles (never remeshed), and a
/// volume bounded by it.
void build_surface(const Boundary& b) {
  const int surface = gmsh::model::addDiscreteEntity(2);
  std::vector<std::size_t> node_tags(std::size_t(b.n_points()));
  for (std::size_t i = 0; i < node_tags.size(); ++i) node_tags[i] = i + 1;
  gmsh::model::mesh::addNodes(2, surface, node_tags, b.points);
  std::vector<std::size_t> tri_tags(std::size_t(b.n_facets())), tri_nodes(b.facets.size());
  for (std::size_t i = 0; i < tri_tags.size(); ++i) tri_tags[i] = i + 1;
  for (std::size_t i = 0; i < tri_nodes.size(); ++i) tri_nodes[i] = std::size_t(b.facets[i]) + 1;
  gmsh::model::mesh::addElementsByType(surface, 2, tri_tags, tri_nodes);
  const int shell = gmsh::model::geo::addSurfaceLoop({surface});
  gmsh::model::geo::addVolume({shell});
  gmsh::model::geo::synchronize();
}

/// One gmsh run in a model of its own: the mesh of `b`.
MeshData run_gmsh(const Boundary& b, const BoundaryMeshOptions& opt, const GradedSize& size) {
  const std::string what = b.dim == 2 ? "polygon" : "surface";
  try {
    ScopedModel model("boundary_mesh");
    ScopedOptions gmsh_options;
    set_options(gmsh_options, b, opt);
    ScopedSizeCallback callback(size);
    if (b.dim == 2)
      build_polygon(b);
    else
      build_surface(b);
    gmsh::logger::start();
    try {
      gmsh::model::mesh::generate(b.dim);
    } catch (...) {
      gmsh::logger::stop();
      throw;
    }
    std::vector<std::string> log;
    gmsh::logger::get(log);
    gmsh::logger::stop();
    for (const auto& line : log)
      if (line.rfind("Error", 0) == 0) mesh_failed("gmsh failed on the " + what + ": " + line);
    return collect(b);
  } catch (const std::string& s) {  // gmsh 4.8 throws std::string
    mesh_failed("gmsh failed on the " + what + ": " + s);
  }
}

// ---- sliver removal (3D) -------------------------------------------------------------------

using core::cross, core::dot, core::sub, core::Vec3;

Vec3 vertex(const MeshData& m, int v) {
  return {m.coords[std::size_t(v) * 3], m.coords[std::size_t(v) * 3 + 1],
          m.coords[std::size_t(v) * 3 + 2]};
}

/// (x1 - x0) . ((x2 - x0) x (x3 - x0)): positive for gmsh's orientation.
double triple(const MeshData& m, int v0, int v1, int v2, int v3) {
  const Vec3 x0 = vertex(m, v0);
  return dot(sub(vertex(m, v1), x0), cross(sub(vertex(m, v2), x0), sub(vertex(m, v3), x0)));
}

/// Quality of a tetrahedron for the clean-up: min(smallest dihedral / 70.53 deg, radius
/// ratio), 1 for the regular tetrahedron, 0 for a flat one.
double tet_quality(const MeshData& m, const std::array<int, 4>& t) {
  std::array<double, 12> x{};
  for (int a = 0; a < 4; ++a)
    for (int k = 0; k < 3; ++k) x[std::size_t(a * 3 + k)] = m.coords[std::size_t(t[a]) * 3 + k];
  const SimplexQuality q = simplex_quality(3, x);
  return std::min(q.min_angle_deg / 70.528779365509308, q.shape);
}

/// Tetrahedra below this quality (smallest dihedral below 14 deg or radius ratio below 0.2) get
/// a clean-up. gmsh's optimiser leaves "caps": tetrahedra spanning two nearly coplanar boundary
/// triangles whose shared edge is the longer diagonal of their quadrilateral (a surface that is
/// not Delaunay there); 1.8 deg on a squashed icosphere, which its own swaps never touch.
constexpr double kSliverQuality = 0.2;

/// Local clean-up of the tetrahedra below kSliverQuality, after gmsh. For each, in order, until
/// it is gone: edge removal on each of its interior edges (remove_edge), moving each of its
/// interior vertices (smooth_vertex), inserting a vertex near it (insert_vertex). Every change
/// must raise the worst tet_quality of the tetrahedra it replaces, never moves or removes a
/// boundary point and keeps every boundary face. New vertices go after the existing ones.
/// Deterministic (fixed visiting order, no randomness).
class SliverRemover {
 public:
  SliverRemover(MeshData& m, const Boundary& b) : m_(m), n_boundary_(int(b.n_points())) {
    for (std::int64_t f = 0; f < b.n_facets(); ++f) {
      const auto t = b.facet(f);
      for (int k = 0; k < 3; ++k) boundary_edges_.insert(std::minmax(t[k], t[(k + 1) % 3]));
      std::array<int, 3> key{t[0], t[1], t[2]};
      std::sort(key.begin(), key.end());
      boundary_faces_.insert(key);
    }
  }

  /// Passes over the slivers until one changes nothing (at most `max_passes`); returns the
  /// number of changes.
  int run(int max_passes) {
    int n_done = 0;
    for (int pass = 0; pass < max_passes; ++pass) {
      const int n = one_pass();
      if (n == 0) break;
      n_done += n;
    }
    return n_done;
  }

 private:
  using Tet = std::array<int, 4>;

  int one_pass() {
    const std::int64_t n_cells = m_.n_cells();
    tets_.resize(std::size_t(n_cells));
    alive_.assign(std::size_t(n_cells), 1);
    for (std::int64_t c = 0; c < n_cells; ++c) {
      for (int a = 0; a < 4; ++a) tets_[c][a] = m_.cells[std::size_t(c) * 4 + a];
      // gmsh's orientation (positive triple product) while we work.
      if (triple(m_, tets_[c][0], tets_[c][1], tets_[c][2], tets_[c][3]) < 0)
        std::swap(tets_[c][1], tets_[c][2]);
    }
    vertex_tets_.assign(std::size_t(m_.n_vertices()), {});
    for (std::int64_t c = 0; c < n_cells; ++c)
      for (int v : tets_[c]) vertex_tets_[v].push_back(int(c));
    int n_done = 0;
    for (std::int64_t c = 0; c < n_cells; ++c) {
      if (!alive_[c] || tet_quality(m_, tets_[c]) >= kSliverQuality) continue;
      for (int a = 0; a < 4 && alive_[c]; ++a)
        for (int e = a + 1; e < 4 && alive_[c]; ++e)
          if (remove_edge(tets_[c][a], tets_[c][e])) ++n_done;
      for (int a = 0; a < 4 && alive_[c]; ++a)
        if (tets_[c][a] >= n_boundary_ && smooth_vertex(tets_[c][a], int(c))) ++n_done;
      if (alive_[c] && insert_vertex(int(c))) ++n_done;
    }
    m_.cells.clear();
    for (std::size_t c = 0; c < tets_.size(); ++c) {
      if (!alive_[c]) continue;
      Tet t = tets_[c];
      std::swap(t[1], t[2]);  // back to PETSc's orientation (negative triple product)
      m_.cells.insert(m_.cells.end(), t.begin(), t.end());
    }
    return n_done;
  }

  /// Edge removal (Shewchuk, "Two discrete optimization algorithms for the topological
  /// improvement of tetrahedral meshes", 2002): the k tetrahedra around the interior edge
  /// (a, b) become 2(k - 2) tetrahedra (a, T) and (b, T), T over the triangulation of the ring
  /// of vertices around the edge that maximises (dynamic programming) the worst tet_quality.
  /// Boundary faces never contain an interior edge, so they are kept. True if it did.
  bool remove_edge(int a, int b) {
    if (boundary_edges_.contains(std::minmax(a, b))) return false;
    // The tetrahedra around (a, b), each as (a, b, p, q) with positive orientation.
    std::vector<int> around;
    std::vector<std::pair<int, int>> pq;
    for (int c : vertex_tets_[a]) {
      if (!alive_[c]) continue;
      const Tet& t = tets_[c];
      if (std::find(t.begin(), t.end(), b) == t.end()) continue;
      // Even permutations of t keep its orientation; find (a, b, p, q) among them.
      static constexpr int kEven[12][4] = {{0, 1, 2, 3}, {0, 2, 3, 1}, {0, 3, 1, 2}, {1, 0, 3, 2},
                                           {1, 2, 0, 3}, {1, 3, 2, 0}, {2, 0, 1, 3}, {2, 1, 3, 0},
                                           {2, 3, 0, 1}, {3, 0, 2, 1}, {3, 1, 0, 2}, {3, 2, 1, 0}};
      for (const auto& perm : kEven)
        if (t[perm[0]] == a && t[perm[1]] == b) pq.emplace_back(t[perm[2]], t[perm[3]]);
      around.push_back(c);
    }
    const int k = int(around.size());
    if (k < 3 || k > 7 || int(pq.size()) != k) return false;
    // The ring p_0 -> q_0 = p_1 -> ... must close after k steps.
    std::vector<int> ring{pq[0].first};
    for (int step = 0; step < k; ++step) {
      const int last = ring.back();
      auto it = std::find_if(pq.begin(), pq.end(), [&](const auto& e) { return e.first == last; });
      if (it == pq.end()) return false;
      ring.push_back(it->second);
    }
    if (ring.back() != ring.front()) return false;
    ring.pop_back();
    if (int(std::set<int>(ring.begin(), ring.end()).size()) != k) return false;

    double old_quality = 1.0;
    for (int c : around) old_quality = std::min(old_quality, tet_quality(m_, tets_[c]));

    // best[i][j]: the best smallest angle over triangulations of ring[i..j] (j - i >= 2).
    // Triangle (i, l, j) gives (a, ri, rl, rj) and (b, ri, rj, rl), both positive if valid.
    auto triangle_quality = [&](int i, int l, int j) {
      const int ri = ring[i], rl = ring[l], rj = ring[j];
      if (triple(m_, a, ri, rl, rj) <= 0 || triple(m_, b, ri, rj, rl) <= 0) return -1.0;
      return std::min(tet_quality(m_, {a, ri, rl, rj}), tet_quality(m_, {b, ri, rj, rl}));
    };
    std::array<std::array<double, 7>, 7> best{};
    std::array<std::array<int, 7>, 7> split{};
    for (int len = 2; len < k; ++len)
      for (int i = 0; i + len < k; ++i) {
        const int j = i + len;
        best[i][j] = -1;
        for (int l = i + 1; l < j; ++l) {
          double q = triangle_quality(i, l, j);
          if (l - i >= 2) q = std::min(q, best[i][l]);
          if (j - l >= 2) q = std::min(q, best[l][j]);
          if (q > best[i][j]) best[i][j] = q, split[i][j] = l;
        }
      }
    if (best[0][k - 1] <= old_quality + 1e-9) return false;

    for (int c : around) alive_[c] = 0;
    std::vector<std::array<int, 2>> stack{{0, k - 1}};
    while (!stack.empty()) {
      const auto [i, j] = stack.back();
      stack.pop_back();
      const int l = split[i][j];
      for (const Tet& t : {Tet{a, ring[i], ring[l], ring[j]}, Tet{b, ring[i], ring[j], ring[l]}}) {
        tets_.push_back(t);
        alive_.push_back(1);
        for (int v : t) vertex_tets_[v].push_back(int(tets_.size()) - 1);
      }
      if (l - i >= 2) stack.push_back({i, l});
      if (j - l >= 2) stack.push_back({l, j});
    }
    return true;
  }

  static std::array<int, 3> sorted_face(const Tet& t, int skip) {
    std::array<int, 3> f{};
    int k = 0;
    for (int a = 0; a < 4; ++a)
      if (a != skip) f[k++] = t[a];
    std::sort(f.begin(), f.end());
    return f;
  }

  /// The living tetrahedron other than c with face f (sorted vertices), or -1.
  int neighbour(int c, const std::array<int, 3>& f) const {
    for (int other : vertex_tets_[f[0]]) {
      if (other == c || !alive_[other]) continue;
      const Tet& t = tets_[other];
      if (std::find(t.begin(), t.end(), f[1]) != t.end() &&
          std::find(t.begin(), t.end(), f[2]) != t.end())
        return other;
    }
    return -1;
  }

  /// True if x lies strictly inside the circumsphere of tetrahedron t.
  bool in_circumsphere(const Tet& t, const Vec3& x) const {
    const Vec3 x0 = vertex(m_, t[0]);
    const Vec3 a = sub(vertex(m_, t[1]), x0), b = sub(vertex(m_, t[2]), x0),
               c = sub(vertex(m_, t[3]), x0);
    const double det = dot(a, cross(b, c));
    if (det == 0) return true;
    const Vec3 bc = cross(b, c), ca = cross(c, a), ab = cross(a, b);
    Vec3 center{};  // relative to x0
    for (int k = 0; k < 3; ++k)
      center[k] = (dot(a, a) * bc[k] + dot(b, b) * ca[k] + dot(c, c) * ab[k]) / (2 * det);
    const Vec3 d = sub(sub(x, x0), center);
    return dot(d, d) < dot(center, center);
  }

  /// Points to try as a new vertex near sliver c: its centroid, and points inwards (along the
  /// mean inward normal of its boundary faces, at fractions of its mean edge) of the centroid
  /// and of each boundary face's centroid.
  std::vector<Vec3> insertion_candidates(int c) const {
    Vec3 inward{0, 0, 0}, centroid{0, 0, 0};
    std::vector<Vec3> bases;  // the centroid and the centroids of the boundary faces
    double edge = 0;
    for (int skip = 0; skip < 4; ++skip) {
      const auto f = sorted_face(tets_[c], skip);
      if (!boundary_faces_.contains(f)) continue;
      const Vec3 x0 = vertex(m_, f[0]), x1 = vertex(m_, f[1]), x2 = vertex(m_, f[2]);
      Vec3 n = cross(sub(x1, x0), sub(x2, x0));
      if (dot(n, sub(vertex(m_, tets_[c][skip]), x0)) < 0) n = {-n[0], -n[1], -n[2]};
      const double len = std::sqrt(dot(n, n));
      for (int k = 0; k < 3; ++k) inward[k] += n[k] / len;
      bases.push_back(
          {(x0[0] + x1[0] + x2[0]) / 3, (x0[1] + x1[1] + x2[1]) / 3, (x0[2] + x1[2] + x2[2]) / 3});
    }
    for (int a = 0; a < 4; ++a) {
      const Vec3 x = vertex(m_, tets_[c][a]);
      for (int k = 0; k < 3; ++k) centroid[k] += x[k] / 4;
      for (int e = a + 1; e < 4; ++e) {
        const Vec3 d = sub(x, vertex(m_, tets_[c][e]));
        edge += std::sqrt(dot(d, d)) / 6;
      }
    }
    std::vector<Vec3> candidates{centroid};
    bases.push_back(centroid);
    const double in_len = std::sqrt(dot(inward, inward));
    if (in_len > 0)
      for (const Vec3& base : bases)
        for (double depth : {0.1, 0.2, 0.35, 0.5, 0.65, 0.8})
          candidates.push_back({base[0] + depth * edge * inward[0] / in_len,
                                base[1] + depth * edge * inward[1] / in_len,
                                base[2] + depth * edge * inward[2] / in_len});
    return candidates;
  }

  /// The Bowyer-Watson cavity of x grown from tetrahedron c: the tetrahedra connected to c
  /// through interior faces whose circumsphere holds x.
  std::vector<int> cavity_of(int c, const Vec3& x) const {
    std::vector<int> cavity{c}, todo{c};
    std::set<int> in_cavity{c};
    while (!todo.empty()) {
      const int t = todo.back();
      todo.pop_back();
      for (int skip = 0; skip < 4; ++skip) {
        const auto f = sorted_face(tets_[t], skip);
        if (boundary_faces_.contains(f)) continue;
        const int u = neighbour(t, f);
        if (u < 0 || in_cavity.contains(u) || !in_circumsphere(tets_[u], x)) continue;
        in_cavity.insert(u);
        cavity.push_back(u);
        todo.push_back(u);
      }
    }
    return cavity;
  }

  /// The cavity's boundary faces (keyed by their sorted vertices), oriented with the cavity on
  /// their positive side.
  std::map<std::array<int, 3>, std::array<int, 3>> cavity_faces(const std::vector<int>& cavity) const {
    std::map<std::array<int, 3>, std::array<int, 3>> faces;
    for (int t : cavity)
      for (int k = 0; k < 4; ++k) {
        const auto key = sorted_face(tets_[t], k);
        if (faces.erase(key)) continue;  // shared by two cavity tetrahedra
        const Tet& v = tets_[t];
        std::array<int, 3> face{};
        int n = 0;
        for (int a = 0; a < 4; ++a)
          if (a != k) face[n++] = v[a];
        if (triple(m_, v[k], face[0], face[1], face[2]) < 0) std::swap(face[1], face[2]);
        faces.emplace(key, face);
      }
    return faces;
  }

  /// The worst tet_quality of the star of x over `faces` (x appended as vertex p while it is
  /// measured), or -1 if a tetrahedron of it is inverted.
  double star_quality(const Vec3& x, int p, const std::map<std::array<int, 3>, std::array<int, 3>>& faces) {
    m_.coords.insert(m_.coords.end(), x.begin(), x.end());
    double q = 1.0;
    for (const auto& [key, f] : faces) {
      if (triple(m_, p, f[0], f[1], f[2]) <= 0) {
        q = -1;
        break;
      }
      q = std::min(q, tet_quality(m_, {p, f[0], f[1], f[2]}));
    }
    m_.coords.resize(m_.coords.size() - 3);
    return q;
  }

  /// Tries to insert a new vertex near sliver c (Bowyer-Watson: the cavity of the point is
  /// replaced by its star); true if it did. The best candidate (insertion_candidates) whose
  /// star is valid must beat the worst tetrahedron it replaces.
  bool insert_vertex(int c) {
    const std::vector<Vec3> candidates = insertion_candidates(c);
    const int p = int(m_.n_vertices());
    double best_gain = 1e-9;
    std::vector<int> best_cavity;
    std::vector<std::array<int, 3>> best_faces;
    int best = -1;
    for (std::size_t i = 0; i < candidates.size(); ++i) {
      const std::vector<int> cavity = cavity_of(c, candidates[i]);
      const auto faces = cavity_faces(cavity);
      double old_quality = 1.0;
      for (int t : cavity) old_quality = std::min(old_quality, tet_quality(m_, tets_[t]));
      const double q = star_quality(candidates[i], p, faces);
      if (q - old_quality > best_gain) {
        best_gain = q - old_quality;
        best = int(i);
        best_cavity = cavity;
        best_faces.clear();
        for (const auto& [key, f] : faces) best_faces.push_back(f);
      }
    }
    if (best < 0) return false;
    m_.coords.insert(m_.coords.end(), candidates[best].begin(), candidates[best].end());
    vertex_tets_.emplace_back();
    for (int t : best_cavity) alive_[t] = 0;
    for (const auto& f : best_faces) {
      tets_.push_back({p, f[0], f[1], f[2]});
      alive_.push_back(1);
      for (int v : tets_.back()) vertex_tets_[v].push_back(int(tets_.size()) - 1);
    }
    return true;
  }

  /// Tries to move interior vertex v (a vertex of sliver c) to improve the worst tetrahedron
  /// around it: towards the centroid of its neighbours (Laplacian), full or half way, or away
  /// from c's opposite face. True if it moved (c itself may still be a sliver).
  bool smooth_vertex(int v, int c) {
    std::vector<int> ball;
    for (int t : vertex_tets_[v])
      if (alive_[t]) ball.push_back(t);
    Vec3 centroid{0, 0, 0};
    double n = 0;
    double old_quality = 1.0;
    for (int t : ball) {
      old_quality = std::min(old_quality, tet_quality(m_, tets_[t]));
      for (int u : tets_[t])
        if (u != v) {
          const Vec3 x = vertex(m_, u);
          for (int k = 0; k < 3; ++k) centroid[k] += x[k];
          n += 1;
        }
    }
    for (int k = 0; k < 3; ++k) centroid[k] /= n;
    const Vec3 x0 = vertex(m_, v);
    // Away from the face of c opposite v: along its normal, by a tenth of c's edges.
    const Tet& tc = tets_[c];
    const int iv = int(std::find(tc.begin(), tc.end(), v) - tc.begin());
    const auto f = sorted_face(tc, iv);
    const Vec3 y0 = vertex(m_, f[0]);
    Vec3 normal = cross(sub(vertex(m_, f[1]), y0), sub(vertex(m_, f[2]), y0));
    if (dot(normal, sub(x0, y0)) < 0) normal = {-normal[0], -normal[1], -normal[2]};
    const double nl = std::sqrt(dot(normal, normal));
    const Vec3 e = sub(x0, y0);
    const double step = 0.1 * std::sqrt(dot(e, e)) / std::max(nl, 1e-300);
    std::vector<Vec3> candidates{
        centroid,
        {(x0[0] + centroid[0]) / 2, (x0[1] + centroid[1]) / 2, (x0[2] + centroid[2]) / 2},
        {x0[0] + step * normal[0], x0[1] + step * normal[1], x0[2] + step * normal[2]}};
    double best_quality = old_quality + 1e-9;
    int best = -1;
    for (std::size_t i = 0; i < candidates.size(); ++i) {
      for (int k = 0; k < 3; ++k) m_.coords[std::size_t(v) * 3 + k] = candidates[i][k];
      double q = 1.0;
      for (int t : ball) {
        const Tet& u = tets_[t];
        if (triple(m_, u[0], u[1], u[2], u[3]) <= 0) {
          q = -1;
          break;
        }
        q = std::min(q, tet_quality(m_, u));
      }
      if (q > best_quality) best_quality = q, best = int(i);
    }
    const Vec3 chosen = best < 0 ? x0 : candidates[best];
    for (int k = 0; k < 3; ++k) m_.coords[std::size_t(v) * 3 + k] = chosen[k];
    return best >= 0;
  }

  MeshData& m_;
  int n_boundary_;  ///< vertices below this are boundary points: never moved
  std::set<std::array<int, 3>> boundary_faces_;
  std::set<std::pair<int, int>> boundary_edges_;
  std::vector<Tet> tets_;
  std::vector<char> alive_;
  std::vector<std::vector<int>> vertex_tets_;
};

}  // namespace

MeshData mesh_boundary(const Boundary& boundary, const BoundaryMeshOptions& options) {
  check_common(boundary, options);
  if (boundary.dim == 2)
    (void)polygon_loop(boundary);
  else
    check_closed_surface(boundary);
  const GradedSize size(boundary.dim, boundary.points, boundary_sizes(boundary, options), options.h,
                        options.grading, 1.0 / edge_per_gmsh_size(boundary.dim));
  MeshData m = run_gmsh(boundary, options, size);
  if (boundary.dim == 3 && options.optimize) SliverRemover(m, boundary).run(3);
  check_boundary(boundary, m);
  return m;
}

}  // namespace hypershape::mesh
