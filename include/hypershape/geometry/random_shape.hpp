#pragma once
/// Random shapes (section 3.1 of the seed paper): a base curve/surface deformed K times by the
/// time-1 flows of stationary Gaussian-random-field velocities, then scaled into [-1, 1]^d.
///
/// The deformed boundary is never built incrementally from a polygon that is then deformed
/// again: the composite map Phi = S o phi_K o ... o phi_1 is a function that can be evaluated
/// anywhere, so the boundary is resolved by refining in the *pre-image* (the angle on the unit
/// circle, the triangles of the base surface) until the image is resolved. Every vertex of the
/// result lies exactly (to round-off) on Phi(base).
#include <array>
#include <functional>
#include <limits>
#include <span>
#include <vector>

#include "hypershape/core/random.hpp"
#include "hypershape/geometry/boundary.hpp"
#include "hypershape/geometry/grid_field.hpp"

namespace hypershape::geometry {

/// One deformation: the velocity has correlation length `sigma` and standard deviation
/// m * velocity_unit per component (see DeformationSpec).
struct DeformationStep {
  double sigma = 0.1;
  double m = 1.0;
};

/// The unit of m when DeformationSpec::velocity_unit is not set: 0.04 in 2D, 0.0125 in 3D
/// (measured side by side against the paper's descriptions; see README, "Random shapes").
double default_velocity_unit(int dim);

/// How the velocity fields are sampled and integrated.
struct DeformationSpec {
  int dim = 2;
  std::vector<DeformationStep> steps;  ///< applied in order (coarse first, as in the paper)
  /// Units of m: the velocity standard deviation is m * velocity_unit (base radius 1). The paper
  /// does not state the unit; NaN (the default) takes default_velocity_unit(dim).
  double velocity_unit = std::numeric_limits<double>::quiet_NaN();
  /// Grid spacing = sigma / nodes_per_sigma; 0 picks 6 in 2D and 3 in 3D (memory: the finest
  /// 3D step of Random3D then has about 2.3M nodes; see README for accuracy).
  double nodes_per_sigma = 0.0;
  /// Grid margin around the shape, in sigmas, on top of 5 standard deviations of v (the farthest
  /// a point travels); 0 picks 3 in 2D and 1 in 3D. Only the trajectories of the shape's points
  /// matter (their domain of dependence under scaling and squaring is the trajectory itself), so
  /// 5 std plus the interpolation stencil suffice; 3D saves a quarter of its nodes with 1.
  double margin_sigmas = 0.0;
};

/// Phi = S o N_K o phi_K o ... o N_1 o phi_1, where each N_k rescales the shape into
/// [-1, 1]^d (so every sigma is measured against the same box, whatever the base's units or
/// the earlier steps did) and S is the final normalisation, fitted to the resolved boundary.
class RandomDeformation {
 public:
  RandomDeformation() = default;
  int dim() const { return dim_; }
  /// The flows and their per-step normalisations, without S; dim coordinates in place.
  void flow(double* x) const;
  /// The full map: flows, then the normalisation S.
  void map(double* x) const;
  /// Sets S so that the box [lo, hi] (in flowed coordinates) becomes centred in [-1, 1]^d with
  /// its largest half-extent equal to 1.
  void normalise_box(std::span<const double> lo, std::span<const double> hi);
  double scale() const { return scale_; }
  std::size_t n_steps() const { return displacements_.size(); }
  const GridField& displacement(std::size_t k) const { return displacements_[k]; }
  int squarings(std::size_t k) const { return squarings_[k]; }

 private:
  friend RandomDeformation sample_deformation(const DeformationSpec&, std::span<const double>,
                                              core::RandomStream&);
  int dim_ = 2;
  std::vector<GridField> displacements_;
  std::vector<int> squarings_;
  std::vector<std::array<double, 4>> step_normalisation_;  ///< centre (3), scale per step
  std::array<double, 3> center_{};
  double scale_ = 1.0;
};

/// Samples the K velocity fields and their flows. `base_points` (n * dim coordinates) is a
/// dense sample of the base boundary, already in [-1, 1]^d: after each step its image is
/// rescaled into [-1, 1]^d, and the grid of each step covers that box plus the margin.
RandomDeformation sample_deformation(const DeformationSpec& spec,
                                     std::span<const double> base_points,
                                     core::RandomStream& rng);

// ---- 2D: the deformed unit circle ---------------------------------------------------------

/// Exact samples of the closed curve theta -> Phi(cos theta, sin theta), theta in [0, 2 pi),
/// counter-clockwise.
struct CurveSamples {
  std::vector<double> theta;
  std::vector<double> xy;  ///< 2 per sample
  std::size_t size() const { return theta.size(); }
};

/// Samples the deformed circle adaptively in theta until every chord is <= `spacing` and the
/// turning angle between consecutive chords is <= `max_turn` radians. Normalises `phi` on the
/// bounding box of the samples (so the curve spans [-1, 1]^2 to within the sampling), and
/// returns the samples in normalised coordinates. `spacing` is in normalised units.
CurveSamples sample_circle_image(RandomDeformation& phi, double spacing, double max_turn);

/// The parameters theta where the curve crosses the circle |x - center| = radius, located by
/// bisection between consecutive samples to round-off.
std::vector<double> circle_crossings(const RandomDeformation& phi, const CurveSamples& curve,
                                     std::span<const double> center, double radius);

/// The polygon: vertices are a subset of the samples plus every `forced` parameter (which
/// become vertices exactly), chosen so that each edge is no longer than the smallest
/// `local_size` of the samples it spans. Counter-clockwise.
Boundary resolve_curve(const RandomDeformation& phi, const CurveSamples& curve,
                       std::span<const double> local_size, std::span<const double> forced);

/// Radius of curvature at every sample (circumradius of the samples about `arm` away on either
/// side; infinite on straight parts).
std::vector<double> curvature_radii(const CurveSamples& curve, double arm);

/// Limits the growth of a periodic size array along the curve: size_i <= size_j + grading *
/// (arc length between i and j).
void grade_sizes(const CurveSamples& curve, std::vector<double>& size, double grading);

// ---- 3D: a deformed closed surface --------------------------------------------------------

/// A closed triangle surface together with its pre-image on the base surface.
struct SurfaceSamples {
  Boundary surface;               ///< images (normalised coordinates), outward triangles
  std::vector<double> preimage;   ///< 3 per point: where each point sits on the base
};

/// How to place a new pre-image point between two others: the unit sphere projects the
/// midpoint radially; a triangulated base keeps the flat midpoint.
enum class BaseKind { sphere, triangulated };

/// Refines `base` (closed, consistently oriented 2-manifold) until every edge of the image under
/// phi is <= `spacing` (normalised units), by longest-edge propagation path bisection in the
/// pre-image (Rivara): an unresolved triangle is refined by bisecting the longest pre-image edge
/// at the end of its LEPP, new pre-image points placed per `kind`. The pre-image triangles stay
/// shape-regular, so the refinement ends wherever phi is continuous, also where the image folds
/// back on itself closer than `spacing`. Normalises `phi` on the bounding box of the result.
/// Throws std::runtime_error beyond `max_points` points (a draw too wild to resolve) or for a
/// base that is not a closed, oriented 2-manifold.
SurfaceSamples sample_surface_image(RandomDeformation& phi, const Boundary& base, BaseKind kind,
                                    double spacing, std::int64_t max_points = 4'000'000);

/// An icosphere: the icosahedron with each triangle split in 4, `level` times, projected onto
/// the unit sphere (10 * 4^level + 2 points). Outward triangles.
Boundary icosphere(int level);

/// The unit circle as a regular polygon with n points (counter-clockwise).
Boundary unit_circle(int n);

}  // namespace hypershape::geometry
