#include "hypershape/mesh/gmsh_mesher.hpp"

#include <gmsh.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <numbers>
#include <unordered_map>

#include "gmsh_util.hpp"
#include "hypershape/core/error.hpp"

namespace hypershape::mesh {

namespace {

using detail::last_gmsh_error;
using detail::restart_gmsh;
using detail::ScopedModel;

int g_sessions = 0;

/// Deterministic, quiet, serial meshing with the size given only by the background field.
void set_common_options(double h) {
  gmsh::option::setNumber("General.Terminal", 0);
  gmsh::option::setNumber("General.NumThreads", 1);  // determinism: same mesh on every run
  gmsh::option::setNumber("Mesh.MeshSizeMax", h);
  gmsh::option::setNumber("Mesh.MeshSizeMin", 0.0);
  gmsh::option::setNumber("Mesh.MeshSizeFromPoints", 0);
  gmsh::option::setNumber("Mesh.MeshSizeFromCurvature", 0);
  gmsh::option::setNumber("Mesh.MeshSizeExtendFromBoundary", 0);
  gmsh::option::setNumber("Mesh.Algorithm", 6);     // Frontal-Delaunay (2D)
  // Delaunay, not HXT: HXT (faster, FACTS.md) gave a different mesh on each call, even with one
  // thread (838/835/837 vertices for the same ball); datasets must be reproducible.
  gmsh::option::setNumber("Mesh.Algorithm3D", 1);
  gmsh::option::setNumber("Mesh.Optimize", 1);
  gmsh::option::setNumber("Mesh.ElementOrder", 1);
}

/// Background size: h_clamp at the clamp ends, growing linearly to h at `clamp_distance`.
void set_clamp_size_field(const MeshOptions& opt, int dim_entities,
                          const std::vector<int>& entity_tags) {
  const double h = opt.h;
  const double hc = opt.clamp_size > 0 ? std::min(opt.clamp_size, h) : h;
  if (entity_tags.empty() || hc >= h) {
    gmsh::option::setNumber("Mesh.MeshSizeMin", h);
    return;
  }
  const double dist = opt.clamp_distance > 0 ? opt.clamp_distance : 4.0 * h;
  const int fd = gmsh::model::mesh::field::add("Distance");
  std::vector<double> tags(entity_tags.begin(), entity_tags.end());
  if (dim_entities == 0) {
    try {
      gmsh::model::mesh::field::setNumbers(fd, "PointsList", tags);
    } catch (...) {
      gmsh::model::mesh::field::setNumbers(fd, "NodesList", tags);
    }
  } else {
    gmsh::model::mesh::field::setNumbers(fd, "CurvesList", tags);
    try {  // gmsh 4.8 calls it NumPointsPerCurve, later versions Sampling
      gmsh::model::mesh::field::setNumber(fd, "NumPointsPerCurve", 200);
    } catch (...) {
      gmsh::model::mesh::field::setNumber(fd, "Sampling", 200);
    }
  }
  const int ft = gmsh::model::mesh::field::add("Threshold");
  gmsh::model::mesh::field::setNumber(ft, "InField", fd);
  gmsh::model::mesh::field::setNumber(ft, "SizeMin", hc);
  gmsh::model::mesh::field::setNumber(ft, "SizeMax", h);
  gmsh::model::mesh::field::setNumber(ft, "DistMin", 0.0);
  gmsh::model::mesh::field::setNumber(ft, "DistMax", dist);
  gmsh::model::mesh::field::setAsBackgroundMesh(ft);
}

double signed_measure(const MeshData& m, const int* c) {
  const double* x0 = &m.coords[std::size_t(c[0]) * m.dim];
  const double* x1 = &m.coords[std::size_t(c[1]) * m.dim];
  const double* x2 = &m.coords[std::size_t(c[2]) * m.dim];
  if (m.dim == 2) return (x1[0] - x0[0]) * (x2[1] - x0[1]) - (x1[1] - x0[1]) * (x2[0] - x0[0]);
  const double* x3 = &m.coords[std::size_t(c[3]) * m.dim];
  const double a[3] = {x1[0] - x0[0], x1[1] - x0[1], x1[2] - x0[2]};
  const double b[3] = {x2[0] - x0[0], x2[1] - x0[1], x2[2] - x0[2]};
  const double d[3] = {x3[0] - x0[0], x3[1] - x0[1], x3[2] - x0[2]};
  return a[0] * (b[1] * d[2] - b[2] * d[1]) - a[1] * (b[0] * d[2] - b[2] * d[0]) +
         a[2] * (b[0] * d[1] - b[1] * d[0]);
}

/// Reads the current model's linear simplices of dimension `dim`, compacts the node numbering
/// to the nodes the cells use (gmsh tags are not contiguous), and orients every cell for PETSc:
/// triangles counter-clockwise, tetrahedra with negative triple product (PETSc's reference
/// tetrahedron is left-handed; raw gmsh tetrahedra get det J < 0 without any complaint).
MeshData extract(int dim) {
  const int type = dim == 2 ? 2 : 4;  // 3-node triangle, 4-node tetrahedron
  const int nv = dim + 1;
  std::vector<std::size_t> node_tags;
  std::vector<double> xyz, param;
  gmsh::model::mesh::getNodes(node_tags, xyz, param, -1, -1, false, false);
  std::unordered_map<std::size_t, std::size_t> node_pos;
  node_pos.reserve(node_tags.size());
  for (std::size_t i = 0; i < node_tags.size(); ++i) node_pos[node_tags[i]] = i;

  std::vector<std::size_t> elem_tags, elem_nodes;
  gmsh::model::mesh::getElementsByType(type, elem_tags, elem_nodes, -1);

  MeshData m;
  m.dim = dim;
  std::unordered_map<std::size_t, int> compact;
  compact.reserve(node_tags.size());
  m.cells.resize(elem_nodes.size());
  for (std::size_t i = 0; i < elem_nodes.size(); ++i) {
    auto [it, inserted] = compact.try_emplace(elem_nodes[i], int(compact.size()));
    if (inserted) {
      const std::size_t p = node_pos.at(elem_nodes[i]);
      for (int k = 0; k < dim; ++k) m.coords.push_back(xyz[3 * p + k]);
    }
    m.cells[i] = it->second;
  }
  for (std::int64_t c = 0; c < m.n_cells(); ++c) {
    int* cell = &m.cells[std::size_t(c) * nv];
    const double s = signed_measure(m, cell);
    const bool flip = dim == 2 ? s < 0 : s > 0;
    if (flip) std::swap(cell[1], cell[2]);
  }
  return m;
}

/// gmsh 4.8 throws std::string (and sometimes nothing): turn both into exceptions we own.
template <class F>
auto guarded(const std::string& what, F&& f) {
  try {
    return f();
  } catch (const std::string& s) {
    throw std::runtime_error("gmsh failed while " + what + ": " + s);
  }
}

}  // namespace

GmshSession::GmshSession() {
  if (g_sessions++ == 0) {
    gmsh::initialize(0, nullptr, false);
    gmsh::option::setNumber("General.Terminal", 0);
  }
}

GmshSession::~GmshSession() {
  if (--g_sessions == 0) gmsh::finalize();
}

bool GmshSession::active() { return g_sessions > 0; }

std::string gmsh_version() {
  std::string v;
  gmsh::option::getString("General.Version", v);
  return v;
}

MeshData mesh_disk(const MeshOptions& opt, const std::optional<ClampRegion>& clamp) {
  return guarded("meshing the unit disk", [&] {
    ScopedModel model("disk");
    set_common_options(opt.h);
    constexpr double pi = std::numbers::pi;
    std::vector<double> angles;
    std::vector<bool> is_clamp_end;
    if (clamp) {
      // x on the circle with |x - c| = r  <=>  x . c = (1 + |c|^2 - r^2) / 2.
      const double cx = clamp->center[0], cy = clamp->center[1];
      const double cn = std::hypot(cx, cy);
      const double k = (1.0 + cn * cn - clamp->radius * clamp->radius) / 2.0;
      if (cn > 0 && std::abs(k / cn) < 1.0) {
        const double phi = std::atan2(cy, cx), delta = std::acos(k / cn);
        angles = {phi - delta, phi + delta};
        is_clamp_end = {true, true};
      }
    }
    if (angles.empty()) {
      angles = {0.0};
      is_clamp_end = {false};
    }
    // Extra points so that every arc spans at most pi/2.
    std::vector<std::pair<double, bool>> pts;
    for (std::size_t i = 0; i < angles.size(); ++i) {
      double a = std::remainder(angles[i], 2 * pi);
      pts.emplace_back(a < 0 ? a + 2 * pi : a, is_clamp_end[i]);
    }
    std::sort(pts.begin(), pts.end());
    std::vector<std::pair<double, bool>> all;
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const double a0 = pts[i].first;
      const double a1 = i + 1 < pts.size() ? pts[i + 1].first : pts[0].first + 2 * pi;
      const int n_sub = std::max(1, int(std::ceil((a1 - a0) / (pi / 2) - 1e-12)));
      all.push_back(pts[i]);
      for (int s = 1; s < n_sub; ++s) all.emplace_back(a0 + (a1 - a0) * s / n_sub, false);
    }
    const int center = gmsh::model::geo::addPoint(0, 0, 0);
    std::vector<int> point_tags, clamp_points;
    for (auto& [a, ce] : all) {
      point_tags.push_back(gmsh::model::geo::addPoint(std::cos(a), std::sin(a), 0));
      if (ce) clamp_points.push_back(point_tags.back());
    }
    std::vector<int> arcs;
    for (std::size_t i = 0; i < point_tags.size(); ++i)
      arcs.push_back(gmsh::model::geo::addCircleArc(point_tags[i], center,
                                                   point_tags[(i + 1) % point_tags.size()]));
    const int loop = gmsh::model::geo::addCurveLoop(arcs);
    gmsh::model::geo::addPlaneSurface({loop});
    gmsh::model::geo::synchronize();
    set_clamp_size_field(opt, 0, clamp_points);
    gmsh::model::mesh::generate(2);
    MeshData m = extract(2);
    if (m.n_cells() == 0) throw std::runtime_error("gmsh produced no triangles for the disk");
    return m;
  });
}

MeshData mesh_ball(const MeshOptions& opt, const std::optional<ClampRegion>& clamp) {
  return guarded("meshing the unit ball", [&] {
    ScopedModel model("ball");
    set_common_options(opt.h);
    const int ball = gmsh::model::occ::addSphere(0, 0, 0, 1.0);
    std::vector<int> clamp_curves;
    if (clamp) {
      // The sphere meets |x - c| = r in the plane x . n = k, n = c/|c|.
      const auto& c = clamp->center;
      const double cn = std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
      const double k = (1.0 + cn * cn - clamp->radius * clamp->radius) / (2.0 * cn);
      if (cn > 0 && std::abs(k) < 1.0) {
        const double n[3] = {c[0] / cn, c[1] / cn, c[2] / cn};
        const int disk = gmsh::model::occ::addDisk(0, 0, 0, 1.5, 1.5);
        // Rotate the xy-disk so its normal (0,0,1) becomes n, then move it to x . n = k.
        const double ax[3] = {-n[1], n[0], 0.0};
        const double axn = std::hypot(ax[0], ax[1]);
        if (axn > 1e-14)
          gmsh::model::occ::rotate({{2, disk}}, 0, 0, 0, ax[0], ax[1], ax[2],
                                   std::atan2(axn, n[2]));
        else if (n[2] < 0)
          gmsh::model::occ::rotate({{2, disk}}, 0, 0, 0, 1, 0, 0, std::numbers::pi);
        gmsh::model::occ::translate({{2, disk}}, k * n[0], k * n[1], k * n[2]);
        gmsh::vectorpair out;
        std::vector<gmsh::vectorpair> out_map;
        gmsh::model::occ::fragment({{3, ball}}, {{2, disk}}, out, out_map);
        gmsh::model::occ::synchronize();
        // Drop the pieces of the cutting disk that lie outside the ball.
        gmsh::vectorpair surfaces;
        gmsh::model::getEntities(surfaces, 2);
        for (auto [d, t] : surfaces) {
          std::vector<int> up, down;
          gmsh::model::getAdjacencies(d, t, up, down);
          if (up.empty()) gmsh::model::occ::remove({{d, t}}, true);
        }
        gmsh::model::occ::synchronize();
        // The clamp curve: every point at distance r from c and on the sphere.
        gmsh::vectorpair curves;
        gmsh::model::getEntities(curves, 1);
        for (auto [d, t] : curves) {
          std::vector<double> lo, hi, x;
          gmsh::model::getParametrizationBounds(d, t, lo, hi);
          gmsh::model::getValue(d, t, {0.5 * (lo[0] + hi[0])}, x);
          const double rr = std::sqrt((x[0] - c[0]) * (x[0] - c[0]) +
                                      (x[1] - c[1]) * (x[1] - c[1]) +
                                      (x[2] - c[2]) * (x[2] - c[2]));
          const double xr = std::sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
          if (std::abs(rr - clamp->radius) < 1e-6 && std::abs(xr - 1.0) < 1e-6)
            clamp_curves.push_back(t);
        }
      }
    }
    gmsh::model::occ::synchronize();
    set_clamp_size_field(opt, 1, clamp_curves);
    gmsh::model::mesh::generate(3);
    MeshData m = extract(3);
    if (m.n_cells() == 0) throw std::runtime_error("gmsh produced no tetrahedra for the ball");
    return m;
  });
}

MeshData mesh_box(int dim, double length, double h) {
  return guarded("meshing a box", [&] {
    ScopedModel model("box");
    set_common_options(h);
    gmsh::option::setNumber("Mesh.MeshSizeMin", h);
    if (dim == 2)
      gmsh::model::occ::addRectangle(0, 0, 0, length, length);
    else
      gmsh::model::occ::addBox(0, 0, 0, length, length, length);
    gmsh::model::occ::synchronize();
    gmsh::model::mesh::generate(dim);
    return extract(dim);
  });
}

MeshData mesh_polygon(const std::vector<std::array<double, 2>>& points, double h) {
  if (points.size() < 3 || !(h > 0)) throw std::invalid_argument("mesh_polygon: needs >= 3 points and h > 0");
  return guarded("meshing a polygon", [&] {
    ScopedModel model("polygon");
    set_common_options(h);
    std::vector<int> tags, lines;
    for (const auto& p : points) tags.push_back(gmsh::model::geo::addPoint(p[0], p[1], 0, h));
    for (std::size_t i = 0; i < tags.size(); ++i)
      lines.push_back(gmsh::model::geo::addLine(tags[i], tags[(i + 1) % tags.size()]));
    gmsh::model::geo::addPlaneSurface({gmsh::model::geo::addCurveLoop(lines)});
    gmsh::model::geo::synchronize();
    gmsh::model::mesh::generate(2);
    MeshData m = extract(2);
    if (m.n_cells() == 0) throw std::runtime_error("gmsh produced no triangles for the polygon");
    return m;
  });
}

MeshData read_mesh_file(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::is_regular_file(path, ec))
    throw core::InputError(path, "", "mesh file does not exist or is not a regular file");
  ScopedModel model("file");
  gmsh::option::setNumber("General.Terminal", 0);
  // gmsh keeps its last error across calls: only a new one speaks about this file.
  const std::string error_before = last_gmsh_error();
  try {
    gmsh::open(path);
  } catch (const std::string& s) {
    restart_gmsh();
    throw core::InputError(path, "", "gmsh could not read the mesh: " + s);
  }
  if (auto err = last_gmsh_error(); err != error_before && err.find("rror") != std::string::npos) {
    restart_gmsh();
    throw core::InputError(path, "", "gmsh could not read the mesh: " + err);
  }
  const int dim = gmsh::model::getDimension();
  if (dim != 2 && dim != 3)
    throw core::InputError(path, "", "the file holds no 2D or 3D mesh (dimension " +
                                         std::to_string(dim) + ")");
  MeshData m = extract(dim);
  if (m.n_cells() == 0)
    throw core::InputError(path, "", dim == 2 ? "the file holds no 3-node triangles"
                                              : "the file holds no 4-node tetrahedra");
  if (dim == 2) {
    // A planar mesh stored with z: keep x, y (extract already did).
  }
  return m;
}

}  // namespace hypershape::mesh
