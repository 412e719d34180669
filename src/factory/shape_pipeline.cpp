#include "hypershape/factory/shape_pipeline.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "hypershape/core/input_error.hpp"
#include "hypershape/core/random.hpp"
#include "hypershape/core/timer.hpp"
#include "hypershape/geometry/boundary_check.hpp"
#include "hypershape/geometry/surface_remesh.hpp"
#include "hypershape/mesh/boundary_mesher.hpp"
#include "hypershape/mesh/surface_file.hpp"

namespace hypershape::factory {

namespace {

/// A draw failed one of the checks: redraw with the next attempt.
struct Rejection {
  std::string stage, reason;
};


std::vector<double> base_sample(const ShapeConfig& c, const std::optional<geometry::Boundary>& base) {
  if (c.dim == 2) return geometry::unit_circle(2048).points;
  if (base) return base->points;
  return geometry::icosphere(4).points;
}

/// 2D: the image of the circle resolved at h (curvature- and neck-limited sizes, graded),
/// conforming to the patch ends; throws Rejection.
geometry::Boundary draw_curve(const ShapeConfig& c, geometry::RandomDeformation& phi, core::RandomStream& patch_rng,
                              ShapeSample& out) {
  const double h = c.h;
  const double min_feature = c.min_feature_fraction * h;
  const double max_turn = c.max_turn_deg * std::numbers::pi / 180.0;
  // Dense exact samples: a quarter of h and a fifth of the turning allowance per chord.
  const geometry::CurveSamples dense = geometry::sample_circle_image(phi, h / 4, max_turn / 5);
  const geometry::Boundary dense_polygon = geometry::polygon_boundary(dense.xy);
  if (const auto check = geometry::check_boundary(dense_polygon); !check.ok)
    throw Rejection{"boundary", check.reason};
  // Local size: h, limited by curvature (turning <= max_turn per edge) and by the interior
  // medial radius (at least two elements across every neck).
  const std::vector<double> radius_in = geometry::inscribed_radii(dense_polygon);
  const std::vector<double> radius_curv = geometry::curvature_radii(dense, h / 16);
  std::vector<double> size(dense.size());
  // A neck is where the inscribed ball is held by the opposite side (its radius is well below
  // the local radius of curvature); a tight bend (tip) is resolved down to min_feature but
  // not rejected: the mesh quality gate decides whether it can be meshed.
  double thinnest = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < size.size(); ++i) {
    if (radius_in[i] < 0.5 * radius_curv[i]) thinnest = std::min(thinnest, radius_in[i]);
    size[i] = std::max(min_feature, std::min({h, radius_curv[i] * max_turn, radius_in[i]}));
  }
  if (thinnest < min_feature)
    throw Rejection{"feature", fmt::format("a neck of half-width {:.3g} is thinner than {:.3g} "
                                           "(min_feature_fraction * h)", thinnest, min_feature)};
  geometry::grade_sizes(dense, size, c.size_grading);
  std::vector<double> forced;
  if (c.dirichlet_radius > 0) {
    out.dirichlet_center = geometry::uniform_boundary_point(dense_polygon, patch_rng);
    // p_D sits on a chord of the dense samples; the exact crossings are on the curve.
    forced = geometry::circle_crossings(phi, dense, {out.dirichlet_center.data(), 2}, c.dirichlet_radius);
  }
  geometry::Boundary b = geometry::resolve_curve(phi, dense, size, forced);
  if (const auto check = geometry::check_boundary(b); !check.ok) throw Rejection{"boundary", check.reason};
  return b;
}

/// 3D: the surface's accepted necks are at least this wide (surfaces are remeshed uniformly at
/// h: a neck must hold two boundary edges across).
double min_neck(const ShapeConfig& c) { return std::max(c.min_feature_fraction * c.h, 0.25 * c.h); }

/// 3D: the simulation surface from the drawn one when they differ (coarser, or refined at the
/// rim), held to the same checks; throws Rejection.
geometry::Boundary simulation_surface(geometry::Boundary b, const ShapeConfig& c, const ShapeSample& out) {
  const double h = c.h, neck = min_neck(c);
  const double surface_h = c.surface_h > 0 ? c.surface_h : c.mesh_h;
  if (surface_h <= h && c.rim_size <= 0) return b;
  // A simulation surface other than the drawn one (coarser, or refined at the rim): the accepted
  // surface remeshed (same clamp sphere), which must pass the same checks; its necks are held to
  // the h-level threshold, so a neck the coarse surface pinches is redrawn rather than solved on.
  const std::string what = fmt::format("remeshed at {:g}{}", std::max(surface_h, h),
                                       c.rim_size > 0 ? fmt::format(" (rim {:g})", c.rim_size) : "");
  try {
    b = solve_surface(b, c, out.dirichlet_center);
  } catch (const std::exception& e) {
    throw Rejection{"boundary", fmt::format("{}: {}", what, e.what())};
  }
  if (const auto check = geometry::check_boundary(b); !check.ok)
    throw Rejection{"boundary", fmt::format("{}: {}", what, check.reason)};
  const std::vector<double> coarse_in = geometry::inscribed_radii(b);
  if (const double t = *std::min_element(coarse_in.begin(), coarse_in.end()); t < neck)
    throw Rejection{"feature", fmt::format("{}, a neck of half-width {:.3g} "
                                           "is thinner than {:.3g}", what, t, neck)};
  return b;
}


/// 3D: the image of the base surface resolved at h in the pre-image, remeshed to h conforming
/// to the patch curve; throws Rejection.
geometry::Boundary draw_surface(const ShapeConfig& c, const std::optional<geometry::Boundary>& base,
                                geometry::RandomDeformation& phi, core::RandomStream& patch_rng, ShapeSample& out) {
  const double h = c.h;
  // 3D: resolve the surface at h in the pre-image, then remesh it to h (conforming to the
  // patch curve), and to mesh_h where the mesh is coarser.
  const geometry::BaseKind kind = base ? geometry::BaseKind::triangulated : geometry::BaseKind::sphere;
  const geometry::Boundary base_surface = base ? *base : geometry::icosphere(3);
  geometry::SurfaceSamples dense;
  try {
    // A Random3D draw needs about 9k points at h = 0.1 (measured; 35k-45k at twice the 3D
    // velocity unit, 200k at the 2D unit, whose draws all fail the checks below). One needing
    // more than 1000 / h^2 (100k at h = 0.1) is rejected before remeshing it costs seconds.
    // A base surface that is already finer than h (a segmentation, say) is hardly refined:
    // its own size must not count against the draw.
    const std::int64_t max_points = std::max<std::int64_t>(
        {50'000, std::int64_t(1'000.0 / (h * h)), 4 * base_surface.n_points()});
    dense = geometry::sample_surface_image(phi, base_surface, kind, h, max_points);
  } catch (const std::runtime_error& e) {
    throw Rejection{"boundary", e.what()};
  }
  geometry::RemeshOptions remesh;
  remesh.target_edge = h;
  if (c.dirichlet_radius > 0) {
    out.dirichlet_center = geometry::uniform_boundary_point(dense.surface, patch_rng);
    remesh.clamp_center = out.dirichlet_center;
    remesh.clamp_radius = c.dirichlet_radius;
  }
  geometry::Boundary b;
  try {
    b = geometry::remesh_surface(dense.surface, remesh);
  } catch (const std::exception& e) {
    throw Rejection{"boundary", e.what()};
  }
  if (const auto check = geometry::check_boundary(b); !check.ok) throw Rejection{"boundary", check.reason};
  const std::vector<double> radius_in = geometry::inscribed_radii(b);
  const double thinnest = *std::min_element(radius_in.begin(), radius_in.end());
  // Surfaces are remeshed uniformly at h (CGAL 5.5 has no adaptive sizing), so a neck must
  // hold at least two boundary edges across.
  const double neck = min_neck(c);
  if (thinnest < neck)
    throw Rejection{"feature", fmt::format("a neck of half-width {:.3g} is thinner than {:.3g} "
                                           "(h / 4: surfaces are resolved uniformly at h)",
                                           thinnest, neck)};
  return simulation_surface(std::move(b), c, out);
}

/// The boundary of one attempt, conforming to the Dirichlet patch; throws Rejection.
geometry::Boundary draw_boundary(const ShapeConfig& c, const std::optional<geometry::Boundary>& base,
                                 std::uint64_t seed, std::int64_t shape_id, int attempt,
                                 ShapeSample& out) {
  core::RandomStream rng(seed, core::Purpose::shape, {std::uint64_t(shape_id), std::uint64_t(attempt)});
  core::RandomStream patch_rng(seed, core::Purpose::dirichlet, {std::uint64_t(shape_id), std::uint64_t(attempt)});
  geometry::DeformationSpec spec = c.deformation;
  spec.dim = c.dim;
  geometry::RandomDeformation phi = geometry::sample_deformation(spec, base_sample(c, base), rng);
  return c.dim == 2 ? draw_curve(c, phi, patch_rng, out) : draw_surface(c, base, phi, patch_rng, out);
}

/// The Dirichlet facets of an accepted draw: those in the patch and in every fixed region
/// (sorted, each once); throws Rejection if a fixed region holds no facet of the boundary.
std::vector<int> dirichlet_facets(const ShapeConfig& c, const ShapeSample& s) {
  std::vector<int> out;
  if (c.dirichlet_radius > 0) {
    std::array<double, 3> p = s.dirichlet_center;
    if (c.dim == 2) p[2] = 0.0;
    out = geometry::facets_in_ball(s.boundary, p, c.dirichlet_radius);
  }
  if (c.fixed_supports.empty()) return out;  // the paper's patch alone: its facets as they were
  const geometry::Boundary& b = s.boundary;
  for (std::size_t k = 0; k < c.fixed_supports.size(); ++k) {
    std::size_t n_in = 0;
    for (std::int64_t f = 0; f < b.n_facets(); ++f) {
      const auto v = b.facet(f);
      double x[9];
      for (int a = 0; a < c.dim; ++a)
        for (int i = 0; i < c.dim; ++i) x[a * c.dim + i] = b.point(v[std::size_t(a)])[i];
      if (c.fixed_supports[k](x, c.dim, c.dim)) out.push_back(int(f)), ++n_in;
    }
    if (n_in == 0) throw Rejection{"support", fmt::format("fixed Dirichlet region {} holds no boundary facet", k)};
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

/// A surface file normalised into [-1, 1]^3. Throws core::InputError.
geometry::Boundary load_surface(const std::string& path) {
  geometry::Boundary b = mesh::read_surface_file(path);
  geometry::normalise_into_box(b);
  return b;
}

}  // namespace

geometry::Boundary solve_surface(const geometry::Boundary& drawn, const ShapeConfig& c,
                                 const std::array<double, 3>& p_d) {
  const double surface_h = std::max(c.surface_h > 0 ? c.surface_h : c.mesh_h, c.h);
  if (surface_h <= c.h && c.rim_size <= 0) return drawn;
  geometry::RemeshOptions remesh;
  remesh.target_edge = surface_h;
  if (c.dirichlet_radius > 0) {
    remesh.clamp_center = p_d;
    remesh.clamp_radius = c.dirichlet_radius;
  }
  if (c.rim_size > 0 && c.dirichlet_radius > 0) {
    const double rim = c.rim_size, g = c.size_grading, r = c.dirichlet_radius;
    remesh.size = [rim, g, r, p_d](const std::array<double, 3>& x) {
      const double d = std::sqrt((x[0] - p_d[0]) * (x[0] - p_d[0]) + (x[1] - p_d[1]) * (x[1] - p_d[1]) +
                                 (x[2] - p_d[2]) * (x[2] - p_d[2]));
      return rim + g * std::abs(d - r);
    };
    remesh.min_edge = 0.5 * rim;
  }
  return geometry::remesh_surface(drawn, remesh);
}

std::optional<geometry::Boundary> load_base(const ShapeConfig& config) {
  if (config.base == "file") return load_surface(config.base_file);
  if (config.base != "directory") return std::nullopt;
  if (config.base_files.empty())
    throw core::InputError(config.base_dir, "", "no surface files (.stl, .msh) in the directory");
  // Every file is read (and so checked) now, not when its shape comes; only the first is kept:
  // a shape reads its own file again (a few ms), so a family of large segmentations does not
  // sit in every rank's memory.
  for (std::size_t i = 1; i < config.base_files.size(); ++i) (void)mesh::read_surface_file(config.base_files[i]);
  return load_surface(config.base_files.front());
}

std::string source_file(const ShapeConfig& config, std::int64_t shape_id) {
  if (config.base != "directory") return "";
  return std::filesystem::path(config.base_files.at(std::size_t(shape_id))).filename().string();
}

geometry::Boundary reference_base(const ShapeConfig& config,
                                  const std::optional<geometry::Boundary>& loaded) {
  if (loaded) return *loaded;
  return config.dim == 2 ? geometry::unit_circle(4096) : geometry::icosphere(4);
}

ShapeSample make_shape(const ShapeConfig& config, const std::optional<geometry::Boundary>& base,
                       std::uint64_t seed, std::int64_t shape_id) {
  ShapeSample out;
  out.shape_id = shape_id;
  // A directory family: this shape's own surface (base, the first file, stays the reference).
  std::optional<geometry::Boundary> own;
  if (config.base == "directory") {
    own = load_surface(config.base_files.at(std::size_t(shape_id)));
    out.source_file = source_file(config, shape_id);
  }
  const std::optional<geometry::Boundary>& surface = own ? own : base;
  const mesh::QualityGate gate = config.quality.min_angle_deg > 0 || config.quality.min_shape > 0
                                     ? config.quality
                                     : mesh::QualityGate::defaults(config.dim);
  for (int attempt = 0; attempt < config.max_attempts; ++attempt) {
    const double t0 = core::now_seconds();
    try {
      out.boundary = draw_boundary(config, surface, seed, shape_id, attempt, out);
      const double t1 = core::now_seconds();
      mesh::BoundaryMeshOptions mopt;
      mopt.h = std::max(config.h, config.mesh_h);
      mopt.point_sizes = geometry::boundary_spacing(out.boundary);
      try {
        out.mesh = mesh::mesh_boundary(out.boundary, mopt);
      } catch (const std::runtime_error& e) {
        throw Rejection{"mesh", e.what()};
      }
      out.quality = mesh::mesh_quality(out.mesh);
      if (std::string why; !mesh::passes(out.quality, gate, &why)) throw Rejection{"quality", why};
      out.attempt = attempt;
      out.dirichlet_radius = config.dirichlet_radius;
      out.dirichlet_facets = dirichlet_facets(config, out);
      if (config.dim == 2 && config.rim_size > 0) {
        try {
          out = grade_shape(out, mopt.h, config.rim_size, config.size_grading);
        } catch (const std::runtime_error& e) {
          throw Rejection{"mesh", fmt::format("graded to the rim {:g}: {}", config.rim_size, e.what())};
        }
        out.quality = mesh::mesh_quality(out.mesh);
        if (std::string why; !mesh::passes(out.quality, gate, &why))
          throw Rejection{"quality", fmt::format("graded to the rim {:g}: {}", config.rim_size, why)};
      }
      const double t2 = core::now_seconds();
      const geometry::Boundary ref = reference_base(config, base);
      // Hausdorff accuracy (3D only): h / 8, i.e. 1.25% of the box half-width at h = 0.1.
      out.metrics = geometry::compute_metrics(out.boundary, &ref, config.h / (config.dim == 2 ? 20 : 8));
      out.seconds_draw = t1 - t0;
      out.seconds_mesh = t2 - t1;
      out.seconds_metrics = core::now_seconds() - t2;
      return out;
    } catch (const Rejection& r) {
      out.rejected.push_back({attempt, r.stage, r.reason});
    }
  }
  std::string why;
  for (const auto& r : out.rejected) why += fmt::format("\n  attempt {} ({}): {}", r.attempt, r.stage, r.reason);
  throw std::runtime_error(fmt::format("shape {} of '{}': no acceptable draw in {} attempts:{}",
                                       shape_id, config.name, config.max_attempts, why));
}

}  // namespace hypershape::factory
