#pragma once
/// Scalar descriptors of a shape given by its Boundary: measures, isoperimetric ratio,
/// Hausdorff distance to another boundary, and the local feature size (inscribed / exterior
/// ball radii) that mesh refinement needs. Serial, no PETSc.
#include <cstdint>
#include <vector>

#include "hypershape/geometry/boundary.hpp"

namespace hypershape::geometry {

/// Enclosed area (2D) or volume (3D), by the divergence theorem over the facets; positive for
/// a correctly oriented boundary (counter-clockwise polygon, outward triangle normals).
/// Throws std::invalid_argument if `b.dim` is not 2 or 3.
double enclosed_measure(const Boundary& b);

/// Perimeter (2D) or surface area (3D). Throws std::invalid_argument if `b.dim` is not 2 or 3.
double boundary_measure(const Boundary& b);

/// 4 pi A / P^2 for a polygon: 1 for a disk, (pi/n)/tan(pi/n) for a regular n-gon, pi/4 for a
/// square; 36 pi V^2 / S^3 for a closed surface (1 for a ball, pi/6 for a cube). Throws
/// std::invalid_argument unless `b.dim` is 2 or 3.
double isoperimetric_ratio(const Boundary& b);

/// One-sided Hausdorff distance sup_{x in from} dist(x, to) between two boundaries of the same
/// dimension (as point sets: curves or surfaces, not the enclosed regions).
///
/// Accuracy guarantee: with H the exact value, the result h satisfies h <= H <= h + tolerance
/// (up to round-off). It is a branch-and-bound over the facets of `from`: dist(., to) is
/// 1-Lipschitz, so on a simplex with vertex values d_i, sup dist <= min_i (d_i + max_j |v_i -
/// v_j|); a simplex is bisected (longest edge) until that bound cannot beat the best sampled
/// value or its diameter is at most `tolerance`. Closest points come from an AABB tree over `to`.
/// Throws std::invalid_argument for tolerance <= 0 or mismatched / unsupported dimensions.
double directed_hausdorff_distance(const Boundary& from, const Boundary& to, double tolerance);

/// Symmetric Hausdorff distance max(directed(a, b), directed(b, a)), with the same guarantee:
/// h <= H <= h + tolerance.
double hausdorff_distance(const Boundary& a, const Boundary& b, double tolerance);

/// For every boundary point i, the radius of the largest ball inside the shape that touches the
/// boundary at point i: the interior medial-ball radius, a local feature size (half the
/// thickness of a neck, the radius of a bend). Same units as the coordinates; one value per point
/// (NaN for a point on no facet). Serial; builds its own AABB tree.
///
/// Shrinking-ball algorithm (Ma, Bae and Kim 2012, on facets instead of a point cloud): the
/// centre moves along the inward vertex normal n; starting from r = the bounding-box diagonal
/// (also the cap), the closest boundary point q to the centre p + r n is found with the AABB tree
/// and r shrinks to the ball through p and q tangent to n, r = |q - p|^2 / (2 n.(q - p)), until
/// the ball is empty. The boundary is read as samples of a smooth shape where it is finely
/// sampled, and literally where its facets are long compared to the ball:
///  - a facet of diameter <= r/2 stands for its vertices: it is ignored while they are outside
///    the ball (its chord then cuts the ball by its sagitta, <= r/32), and the ball shrinks to
///    its inside vertex otherwise; a longer facet counts with all its points;
///  - the flat regions (connected coplanar / collinear facets) at p are ignored: they are tangent
///    to every candidate ball where the boundary is smooth at p; at a convex corner they would
///    shrink the ball to 0, so a corner vertex gets its bisector ball instead;
///  - n uses Max's weights (facet normal / squared lengths of its edges at p), exact when p and
///    its neighbours lie on a circle or a sphere.
/// Measured: exact (to round-off) for a regular polygon or an icosphere (vertices on the
/// circle / sphere); w/2 on the long sides of a w-wide strip for any sampling of the sides; the
/// curvature radius b^2/a at the tip of an ellipse to 0.3% with 100 vertices, from above.
/// Near a convex corner, as for the exact medial axis, the radius tends to 0 like the distance
/// to the corner (a sample t away from a right-angle corner gets about t). A strip of width w
/// whose opposite sides are sampled more than 16 w apart may get a radius up to L^2 / (8 w).
std::vector<double> inscribed_radii(const Boundary& b);

/// The same with the outward normal: radius of the largest ball outside the shape touching the
/// boundary at each point, capped at the bounding-box diagonal (convex parts get the cap). A
/// small value flags near-touching lobes or a narrow gap (a gap of width g gives g/2); as above,
/// it also tends to 0 next to a corner of the outside (an inward corner of the shape).
std::vector<double> exterior_radii(const Boundary& b);

/// Descriptors of one shape, as stored with a data set.
struct ShapeMetrics {
  double measure = 0;                  ///< enclosed area (2D) / volume (3D)
  double boundary_measure = 0;         ///< perimeter (2D) / surface area (3D)
  double isoperimetric_ratio = 0;      ///< 4 pi A / P^2 in 2D, 36 pi V^2 / S^3 in 3D (1: disk, ball)
  double hausdorff_to_base = 0;        ///< symmetric Hausdorff distance to the base; NaN if none
  std::int64_t n_boundary_facets = 0;  ///< segments (2D) / triangles (3D)
  double min_local_feature_size = 0;   ///< min over points of inscribed_radii()
  double min_exterior_gap = 0;         ///< min over points of exterior_radii() (a radius: half
                                       ///< the width of the narrowest gap)
};

/// All of ShapeMetrics for `shape`. `base` (may be nullptr) is the shape it was derived from;
/// the Hausdorff distance is computed to `hausdorff_tolerance` (see hausdorff_distance). Throws
/// std::invalid_argument as the functions above.
ShapeMetrics compute_metrics(const Boundary& shape, const Boundary* base,
                             double hausdorff_tolerance);

}  // namespace hypershape::geometry
