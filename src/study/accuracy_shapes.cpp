// The scenes' shapes at every h of the accuracy study (see ShapeCache in accuracy_detail.hpp).
#include <fmt/format.h>

#include <cmath>

#include "accuracy_detail.hpp"
#include "hypershape/core/timer.hpp"
#include "hypershape/geometry/boundary_check.hpp"
#include "hypershape/geometry/random_shape.hpp"
#include "hypershape/geometry/surface_remesh.hpp"
#include "hypershape/mesh/boundary_mesher.hpp"
#include "hypershape/mesh/quality.hpp"

namespace hypershape::study::accuracy {

std::string fmt_g(double v) { return fmt::format("{:g}", v); }

config::DatasetConfig scene_config(const SceneSpec& s, const std::string& override_yaml) {
  // The study refines uniformly with the seed's pointwise material: the random3d preset's clamp
  // rim and mean dilatation (since 2026-11-25) are measured by study_labels3d instead, and the 2D
  // presets' grading at the patch ends (mesh.rim, since 2026-11-29) by study_error_estimate
  // (one absolute rim at every h would not be a uniform refinement).
  const bool r3 = s.preset == "random3d" && override_yaml.find("material") == std::string::npos;
  auto c = config::parse_dataset_text("preset: " + s.preset + "\n" + override_yaml + "\n" +
                                          (r3 ? "material: {dilatation: pointwise}\n" : ""),
                                      "<study_accuracy --override>");
  c.shapes.rim_size = 0;
  if (s.preset == "random3d") c.shapes.surface_h = 0;
  return c;
}

double preset_mesh_h(const config::DatasetConfig& cfg) { return std::max(cfg.shapes.h, cfg.shapes.mesh_h); }

const factory::ShapeSample& ShapeCache::at(double h, bool graded) {
  graded = graded && kind_ == SceneKind::disk && grade_end_ < 1.0;
  for (auto& [key, s] : shapes_)
    if (std::abs(key.first - h) < 1e-12 && key.second == graded) return *s;
  const double t0 = core::now_seconds();
  auto s = std::make_unique<factory::ShapeSample>(build(h, graded));
  shapes_.emplace_back(std::make_pair(h, graded), std::move(s));
  seconds_.push_back({{h, graded}, core::now_seconds() - t0});
  return *shapes_.back().second;
}

double ShapeCache::seconds(double h, bool graded) const {
  graded = graded && kind_ == SceneKind::disk && grade_end_ < 1.0;
  for (auto& [key, s] : seconds_)
    if (std::abs(key.first - h) < 1e-12 && key.second == graded) return s;
  return NAN;
}

factory::ShapeSample ShapeCache::finish(geometry::Boundary b, const std::array<double, 3>& p_d, double h) const {
  if (const auto check = geometry::check_boundary(b); !check.ok)
    throw std::runtime_error("boundary at h " + fmt_g(h) + ": " + check.reason);
  factory::ShapeSample out;
  out.shape_id = id_;
  out.boundary = std::move(b);
  mesh::BoundaryMeshOptions mo;
  mo.h = h;
  mo.grading = config_.size_grading;
  out.mesh = mesh::mesh_boundary(out.boundary, mo);
  out.quality = mesh::mesh_quality(out.mesh);
  out.dirichlet_center = p_d;
  out.dirichlet_radius = config_.dirichlet_radius;
  out.dirichlet_facets = geometry::facets_in_ball(out.boundary, p_d, config_.dirichlet_radius);
  return out;
}

namespace {

/// Parameters in [t0, t1) of the points of a unit-circle arc: chords of h_end at both ends,
/// growing at rate `grading` per unit length, at most h (equidistributed in 1 / size).
std::vector<double> arc_parameters(double t0, double t1, double h, double h_end, double grading) {
  const double L = t1 - t0;
  const int n = 20000;
  std::vector<double> cum(n + 1, 0.0);
  auto size = [&](double s) { return std::min(h, h_end + grading * std::min(s, L - s)); };
  for (int i = 0; i < n; ++i) {
    const double s = (i + 0.5) * L / n;
    cum[std::size_t(i) + 1] = cum[std::size_t(i)] + (L / n) / size(s);
  }
  const int m = std::max(1, int(std::ceil(cum[n])));
  std::vector<double> out;
  for (int k = 0, i = 0; k < m; ++k) {
    const double target = cum[n] * k / m;
    while (cum[std::size_t(i) + 1] < target) ++i;
    const double w = (target - cum[std::size_t(i)]) / (cum[std::size_t(i) + 1] - cum[std::size_t(i)]);
    out.push_back(t0 + (i + w) * L / n);
  }
  return out;
}

constexpr std::array<double, 3> e1{1.0, 0.0, 0.0};

}  // namespace

factory::ShapeSample ShapeCache::build_disk(double h, bool graded) const {
  // |x - p_D| = r on the unit circle at angle +-theta_c: 2 - 2 cos theta_c = r^2. Each arc
  // (the patch and the rest) is split into chords of at most h; graded (references only):
  // chords of grade_end * h at the patch ends, growing by size_grading per unit length.
  const double r = config_.dirichlet_radius;
  const double tc = std::acos(1.0 - 0.5 * r * r);
  const double pi = std::acos(-1.0);
  const double h_end = graded ? grade_end_ * h : h;
  std::vector<double> xy;
  for (auto [t0, t1] : {std::pair{-tc, tc}, std::pair{tc, 2 * pi - tc}})
    for (double t : arc_parameters(t0, t1, h, h_end, config_.size_grading))
      xy.insert(xy.end(), {std::cos(t), std::sin(t)});
  return finish(geometry::polygon_boundary(std::move(xy)), e1, h);
}

factory::ShapeSample ShapeCache::build_ball(double h) {
  if (!sphere_) sphere_ = geometry::icosphere(6);  // edges ~0.016: sagitta ~3e-5
  geometry::RemeshOptions ro;
  ro.target_edge = h;
  ro.clamp_center = e1;
  ro.clamp_radius = config_.dirichlet_radius;
  return finish(geometry::remesh_surface(*sphere_, ro), e1, h);
}

factory::ShapeSample ShapeCache::build_random3d(double h) {
  // The factory's own coarse mesh (ShapeConfig::mesh_h): the shape drawn at the finest
  // h, its surface remeshed at h with the same clamp sphere. The draw must not change
  // with h (a coarse surface failing its checks would make the factory redraw).
  auto c = config_;
  c.h = finest_h_;
  c.mesh_h = h;
  auto out = factory::make_shape(c, std::nullopt, seed_, id_);
  if (!attempt_) attempt_ = out.attempt;
  if (out.attempt != *attempt_)
    throw std::runtime_error("random3d shape " + std::to_string(id_) + " at h " + fmt_g(h) +
                             ": the coarse surface fails the factory's checks (draw " + std::to_string(out.attempt) +
                             " instead of " + std::to_string(*attempt_) + ")");
  return out;
}

factory::ShapeSample ShapeCache::build(double h, bool graded) {
  switch (kind_) {
    case SceneKind::disk: return build_disk(h, graded);
    case SceneKind::ball: return build_ball(h);
    case SceneKind::random2d: {
      auto c = config_;
      c.h = h;
      // The neck test at the preset's absolute threshold (min_feature_fraction x the preset's
      // h) at every h: it decides which draw is accepted, and the same draw must be accepted
      // at every h (at 3x the preset's h, Random2D shape 0 and OODRandom2D shapes 0-19 fail
      // the test at its default fraction).
      c.min_feature_fraction = config_.min_feature_fraction * config_.h / h;
      return factory::make_shape(c, std::nullopt, seed_, id_);
    }
    case SceneKind::random3d: return build_random3d(h);
  }
  throw std::logic_error("scene kind");
}

void check_same_draw(const factory::ShapeSample& shape, const factory::ShapeSample& base, double h) {
  if (shape.attempt == base.attempt) return;
  std::string why;
  for (const auto& r : (shape.attempt > base.attempt ? shape : base).rejected)
    why += fmt::format("; attempt {} ({}): {}", r.attempt, r.stage, r.reason);
  throw std::runtime_error(fmt::format("the draw at h {} is attempt {}, the baseline's attempt {}{}", h, shape.attempt,
                                       base.attempt, why));
}

}  // namespace hypershape::study::accuracy
