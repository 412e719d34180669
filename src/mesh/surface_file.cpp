#include "hypershape/mesh/surface_file.hpp"

#include <gmsh.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <unordered_map>
#include <vector>

#include "gmsh_util.hpp"
#include "hypershape/core/input_error.hpp"
#include "hypershape/geometry/boundary_check.hpp"

namespace hypershape::mesh {

namespace {

const std::string k_allowed =
    "allowed: one closed, 2-manifold, consistently oriented, non-self-intersecting triangle "
    "surface in STL (ASCII or binary) or gmsh .msh";

[[noreturn]] void bad_file(const std::string& path, const std::string& message) {
  throw core::InputError(path, "", message + " (" + k_allowed + ")");
}

/// Merges points closer than `tol` (max-norm), keeping the first one met: a hash grid of cell
/// size tol, probing the 27 cells around each point.
class Welder {
 public:
  explicit Welder(double tol) : tol_(tol) {}

  /// Index of the point equal (to tol) to x, adding it if new.
  int find_or_add(const std::array<double, 3>& x) {
    std::array<std::int64_t, 3> cell;
    for (int k = 0; k < 3; ++k) cell[k] = std::int64_t(std::floor(x[k] / tol_));
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          auto it = grid_.find(key({cell[0] + dx, cell[1] + dy, cell[2] + dz}));
          if (it == grid_.end()) continue;
          for (int i : it->second) {
            const double* p = &points_[3 * std::size_t(i)];
            if (std::abs(p[0] - x[0]) <= tol_ && std::abs(p[1] - x[1]) <= tol_ &&
                std::abs(p[2] - x[2]) <= tol_)
              return i;
          }
        }
    const int i = int(points_.size() / 3);
    points_.insert(points_.end(), x.begin(), x.end());
    grid_[key(cell)].push_back(i);
    return i;
  }
  std::vector<double>& points() { return points_; }

 private:
  static std::uint64_t key(const std::array<std::int64_t, 3>& c) {
    std::uint64_t h = 1469598103934665603ull;
    for (auto v : c) h = (h ^ std::uint64_t(v)) * 1099511628211ull;
    return h;
  }
  double tol_;
  std::vector<double> points_;
  std::unordered_map<std::uint64_t, std::vector<int>> grid_;  // hash collisions are harmless
};

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char ch) { return char(std::tolower(ch)); });
  return ext;
}

bool is_surface_extension(const std::string& ext) { return ext == ".stl" || ext == ".msh"; }

}  // namespace

std::vector<std::string> surface_files_in(const std::string& dir) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::exists(dir, ec)) throw core::InputError(dir, "", "no such directory");
  if (!fs::is_directory(dir, ec)) throw core::InputError(dir, "", "not a directory");
  std::vector<std::string> names;
  try {
    for (const fs::directory_entry& e : fs::directory_iterator(dir)) {
      const std::string name = e.path().filename().string();
      if (name.empty() || name.front() == '.' || !e.is_regular_file()) continue;
      if (is_surface_extension(lower_extension(name))) names.push_back(name);
    }
  } catch (const fs::filesystem_error& e) {
    throw core::InputError(dir, "", std::string("cannot list the directory: ") + e.code().message());
  }
  std::sort(names.begin(), names.end());
  std::vector<std::string> paths;
  for (const std::string& name : names) paths.push_back((fs::path(dir) / name).string());
  return paths;
}

namespace {

/// Loads `path` into the current gmsh model; an unreadable file is an input error naming it.
void merge_into_gmsh(const std::string& path) {
  gmsh::option::setNumber("General.Terminal", 0);
  // gmsh keeps its last error across calls: only a new one speaks about this file.
  const std::string error_before = detail::last_gmsh_error();
  try {
    gmsh::merge(path);
  } catch (const std::string& s) {
    detail::restart_gmsh();
    bad_file(path, "gmsh could not read the file: " + s);
  }
  if (auto err = detail::last_gmsh_error(); err != error_before && err.find("rror") != std::string::npos) {
    detail::restart_gmsh();
    bad_file(path, "gmsh could not read the file: " + err);
  }
}

/// The model's nodes and its triangles' corner nodes (3- and 6-node triangles); quadrangles refused.
struct GmshTriangles {
  std::vector<std::size_t> node_tags, tri_nodes;
  std::vector<double> xyz;
};

GmshTriangles read_triangles(const std::string& path) {
  GmshTriangles t;
  std::size_t n_quads = 0;
  try {
    std::vector<double> param;
    gmsh::model::mesh::getNodes(t.node_tags, t.xyz, param, -1, -1, false, false);
    // gmsh 4.8 leaves the output vectors as they were when there is no element of the type.
    std::vector<std::size_t> tags, nodes;
    gmsh::model::mesh::getElementsByType(2, tags, t.tri_nodes, -1);  // 3-node triangles
    tags.clear();
    nodes.clear();
    gmsh::model::mesh::getElementsByType(9, tags, nodes, -1);  // 6-node: keep the corners
    for (std::size_t e = 0; e + 6 <= nodes.size(); e += 6)
      t.tri_nodes.insert(t.tri_nodes.end(), nodes.begin() + std::ptrdiff_t(e), nodes.begin() + std::ptrdiff_t(e + 3));
    for (int quad_type : {3, 10, 16}) {  // 4-, 9- and 8-node quadrangles
      tags.clear();
      nodes.clear();
      gmsh::model::mesh::getElementsByType(quad_type, tags, nodes, -1);
      n_quads += tags.size();
    }
  } catch (const std::string& s) {
    detail::restart_gmsh();
    bad_file(path, "gmsh could not read the mesh in the file: " + s);
  }
  if (n_quads > 0)
    bad_file(path, "the file holds " + std::to_string(n_quads) + " quadrangles; only triangles are allowed");
  if (t.tri_nodes.empty()) bad_file(path, "the file holds no triangles");
  return t;
}

/// The triangles as a boundary: every referenced node present and finite, coincident points
/// welded (STL stores each triangle's corners separately), points numbered in order of first
/// use (which drops nodes that no triangle uses).
geometry::Boundary weld(const std::string& path, const GmshTriangles& t) {
  std::unordered_map<std::size_t, std::size_t> node_pos;
  node_pos.reserve(t.node_tags.size());
  for (std::size_t i = 0; i < t.node_tags.size(); ++i) node_pos[t.node_tags[i]] = i;
  double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
  for (std::size_t tag : t.tri_nodes) {
    auto it = node_pos.find(tag);
    if (it == node_pos.end()) bad_file(path, "a triangle refers to node " + std::to_string(tag) + ", which is missing");
    for (int k = 0; k < 3; ++k) {
      const double x = t.xyz[3 * it->second + k];
      if (!std::isfinite(x)) bad_file(path, "node " + std::to_string(tag) + " is not finite");
      lo[k] = std::min(lo[k], x);
      hi[k] = std::max(hi[k], x);
    }
  }
  const double diag = std::hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
  if (!(diag > 0)) bad_file(path, "all the triangles' points coincide");
  Welder welder(1e-9 * diag);
  geometry::Boundary b;
  b.dim = 3;
  b.facets.reserve(t.tri_nodes.size());
  for (std::size_t tag : t.tri_nodes) {
    const std::size_t p = node_pos[tag];
    b.facets.push_back(welder.find_or_add({t.xyz[3 * p], t.xyz[3 * p + 1], t.xyz[3 * p + 2]}));
  }
  b.points = std::move(welder.points());
  return b;
}

/// Outward: flips every triangle if the enclosed volume is negative (only meaningful when the
/// orientation is consistent, which check_boundary then verifies).
void orient_outward(geometry::Boundary& b) {
  double vol6 = 0;
  for (std::int64_t f = 0; f < b.n_facets(); ++f) {
    const double* a = &b.points[3 * std::size_t(b.facets[3 * f])];
    const double* c = &b.points[3 * std::size_t(b.facets[3 * f + 1])];
    const double* d = &b.points[3 * std::size_t(b.facets[3 * f + 2])];
    vol6 += a[0] * (c[1] * d[2] - c[2] * d[1]) - a[1] * (c[0] * d[2] - c[2] * d[0]) + a[2] * (c[0] * d[1] - c[1] * d[0]);
  }
  if (vol6 < 0)
    for (std::size_t f = 0; f < b.facets.size(); f += 3) std::swap(b.facets[f + 1], b.facets[f + 2]);
}

}  // namespace

geometry::Boundary read_surface_file(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) bad_file(path, "surface file does not exist or is not a regular file");
  const std::string ext = lower_extension(path);
  if (!is_surface_extension(ext))
    bad_file(path, "unsupported surface file extension '" + ext + "' (.stl or .msh expected)");
  detail::ScopedModel model("surface_file");
  merge_into_gmsh(path);
  geometry::Boundary b = weld(path, read_triangles(path));
  orient_outward(b);
  if (const auto check = geometry::check_boundary(b); !check.ok)
    bad_file(path, "not a valid closed surface: " + check.reason);
  return b;
}

}  // namespace hypershape::mesh
