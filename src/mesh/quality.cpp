#include "hypershape/mesh/quality.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>

#include "hypershape/core/vec3.hpp"

namespace hypershape::mesh {

namespace {

using core::cross, core::dot, core::norm, core::sub, core::Vec3;

/// Angle in degrees between u and v from their cross and dot products (accurate near 0 and pi,
/// where acos is not).
double angle_deg(const Vec3& u, const Vec3& v) {
  return std::atan2(norm(cross(u, v)), dot(u, v)) * 180.0 / std::numbers::pi;
}

SimplexQuality triangle(const std::array<Vec3, 4>& x) {
  SimplexQuality f{180.0, 0.0, std::numeric_limits<double>::max(), 0.0, 0.0};
  double sum_sq = 0;
  for (int a = 0; a < 3; ++a) {
    const double l = norm(sub(x[(a + 1) % 3], x[a]));
    f.min_edge = std::min(f.min_edge, l), f.max_edge = std::max(f.max_edge, l);
    sum_sq += l * l;
    f.min_angle_deg =
        std::min(f.min_angle_deg, angle_deg(sub(x[(a + 1) % 3], x[a]), sub(x[(a + 2) % 3], x[a])));
  }
  const double twice_area = cross(sub(x[1], x[0]), sub(x[2], x[0]))[2];
  f.signed_measure = twice_area / 2;  // PETSc: counter-clockwise is positive
  // 4 sqrt(3) area / sum of squared edges
  f.shape = sum_sq > 0 ? 2.0 * std::sqrt(3.0) * std::abs(twice_area) / sum_sq : 0.0;
  return f;
}

SimplexQuality tetrahedron(const std::array<Vec3, 4>& x) {
  SimplexQuality f{180.0, 0.0, std::numeric_limits<double>::max(), 0.0, 0.0};
  for (int a = 0; a < 4; ++a)
    for (int b = a + 1; b < 4; ++b) {
      const double l = norm(sub(x[b], x[a]));
      f.min_edge = std::min(f.min_edge, l), f.max_edge = std::max(f.max_edge, l);
    }
  const double triple = dot(sub(x[1], x[0]), cross(sub(x[2], x[0]), sub(x[3], x[0])));
  f.signed_measure = -triple / 6;  // PETSc's reference tetrahedron is left-handed
  // n[k]: normal of the face opposite vertex k, pointing towards k (inwards); the dihedral angle
  // at the edge shared by faces k and l is the angle between -n[k] and n[l].
  std::array<Vec3, 4> n;
  double area_sum = 0;
  for (int k = 0; k < 4; ++k) {
    const Vec3& p = x[(k + 1) % 4];
    n[k] = cross(sub(x[(k + 2) % 4], p), sub(x[(k + 3) % 4], p));
    if (dot(n[k], sub(x[k], p)) < 0) n[k] = {-n[k][0], -n[k][1], -n[k][2]};
    area_sum += 0.5 * norm(n[k]);
  }
  for (int k = 0; k < 4; ++k)
    for (int l = k + 1; l < 4; ++l)
      f.min_angle_deg = std::min(f.min_angle_deg, angle_deg({-n[k][0], -n[k][1], -n[k][2]}, n[l]));
  // Radius ratio 3 r_in / R_circ with r_in = 3 V / area and
  // R_circ = sqrt((p+q+r)(p+q-r)(p-q+r)(-p+q+r)) / (24 V), p, q, r the products of the lengths
  // of opposite edges.
  const double volume = std::abs(triple) / 6.0;
  const double p = norm(sub(x[1], x[0])) * norm(sub(x[3], x[2]));
  const double q = norm(sub(x[2], x[0])) * norm(sub(x[3], x[1]));
  const double r = norm(sub(x[3], x[0])) * norm(sub(x[2], x[1]));
  const double prod = std::max(0.0, (p + q + r) * (p + q - r) * (p - q + r) * (-p + q + r));
  f.shape = volume > 0 && prod > 0 && area_sum > 0
                ? std::min(1.0, 216.0 * volume * volume / (area_sum * std::sqrt(prod)))
                : 0.0;
  return f;
}

std::string format(double v) {
  std::ostringstream s;
  s.precision(4);
  s << v;
  return s.str();
}

}  // namespace

SimplexQuality simplex_quality(int dim, std::span<const double> x) {
  std::array<Vec3, 4> p{};
  for (int a = 0; a <= dim; ++a)
    for (int k = 0; k < dim; ++k) p[a][k] = x[std::size_t(a * dim + k)];
  return dim == 2 ? triangle(p) : tetrahedron(p);
}

MeshQuality mesh_quality(const MeshData& mesh) {
  MeshQuality q;
  q.n_cells = mesh.n_cells();
  q.n_vertices = mesh.n_vertices();
  if (q.n_cells == 0 || (mesh.dim != 2 && mesh.dim != 3)) return q;
  q.min_angle_deg = 180.0;
  q.min_shape = std::numeric_limits<double>::max();
  q.min_edge = std::numeric_limits<double>::max();
  const int nv = mesh.dim + 1;
  std::array<double, 12> x{};
  for (std::int64_t c = 0; c < q.n_cells; ++c) {
    for (int a = 0; a < nv; ++a)
      for (int k = 0; k < mesh.dim; ++k)
        x[std::size_t(a * mesh.dim + k)] =
            mesh.coords[std::size_t(mesh.cells[std::size_t(c) * nv + a]) * mesh.dim + k];
    const SimplexQuality f = simplex_quality(mesh.dim, {x.data(), std::size_t(nv * mesh.dim)});
    q.min_angle_deg = std::min(q.min_angle_deg, f.min_angle_deg);
    q.min_shape = std::min(q.min_shape, f.shape);
    q.min_edge = std::min(q.min_edge, f.min_edge);
    q.max_edge = std::max(q.max_edge, f.max_edge);
    q.n_inverted += f.signed_measure <= 0;
  }
  return q;
}

QualityGate QualityGate::defaults(int dim) {
  if (dim == 2) return {18.0, 0.5};
  return {8.0, 0.12};
}

bool passes(const MeshQuality& q, const QualityGate& gate, std::string* reason) {
  std::string why;
  if (q.n_cells == 0)
    why = "no cells";
  else if (q.n_inverted > 0)
    why = std::to_string(q.n_inverted) + " inverted cells";
  else if (q.min_angle_deg < gate.min_angle_deg)
    why = "min angle " + format(q.min_angle_deg) + " deg < " + format(gate.min_angle_deg) + " deg";
  else if (q.min_shape < gate.min_shape)
    why = "min shape " + format(q.min_shape) + " < " + format(gate.min_shape);
  if (reason) *reason = why;
  return why.empty();
}

}  // namespace hypershape::mesh
