/// A dead pressure on the organ surface (configs/surfaces/organ.stl, the AugLiver stand-in, as
/// configs/examples/organ_pressure3d.yaml loads it): its resultant on a region is -p times the
/// region's area vector sum_f A_f N_f (computed here from the surface triangles, not by the
/// facet quadrature under test), and on the whole free boundary of the closed surface it is +p
/// times the clamped facets' area vector (the closed surface's area vector is zero). P2, on 1,
/// 2 and 3 ranks (the mpi binary): every facet is assembled on exactly one rank.
#include <catch2/catch.hpp>
#include <array>
#include <cmath>

#include "hypershape/geometry/boundary.hpp"
#include "hypershape/geometry/surface_remesh.hpp"
#include "hypershape/mesh/boundary_mesher.hpp"
#include "hypershape/mesh/surface_file.hpp"
#include "hypershape/physics/region.hpp"
#include "support/helpers.hpp"

using namespace hypershape;

namespace {

using Vec3 = std::array<double, 3>;

/// The organ normalised into [-1, 1]^3 and remeshed at edge 0.3 (the factory's steps without
/// the random deformation).
geometry::Boundary organ_surface() {
  geometry::Boundary b = mesh::read_surface_file(std::string(HS_SOURCE_DIR) + "/configs/surfaces/organ.stl");
  geometry::normalise_into_box(b);
  geometry::RemeshOptions o;
  o.target_edge = 0.3;
  return geometry::remesh_surface(b, o);
}

/// sum of A_f N_f (= half the cross product of two edges) over the facets that pass `in` and
/// fail `out` (when given).
Vec3 area_vector(const geometry::Boundary& b, const physics::FacetPredicate& in,
                 const physics::FacetPredicate& out = {}) {
  Vec3 s{0, 0, 0};
  for (std::int64_t f = 0; f < b.n_facets(); ++f) {
    double x[9];
    for (int a = 0; a < 3; ++a)
      for (int k = 0; k < 3; ++k) x[3 * a + k] = b.point(b.facet(f)[a])[k];
    if ((in && !in(x, 3, 3)) || (out && out(x, 3, 3))) continue;
    const double e1[3] = {x[3] - x[0], x[4] - x[1], x[5] - x[2]}, e2[3] = {x[6] - x[0], x[7] - x[1], x[8] - x[2]};
    s[0] += 0.5 * (e1[1] * e2[2] - e1[2] * e2[1]);
    s[1] += 0.5 * (e1[2] * e2[0] - e1[0] * e2[2]);
    s[2] += 0.5 * (e1[0] * e2[1] - e1[1] * e2[0]);
  }
  return s;
}

/// The applied force at u = 0, load factor 1, of the organ clamped on `clamp` under `pressure`.
Vec3 applied_force(const mesh::MeshData& m, const physics::Region& clamp, physics::EffectPtr pressure) {
  std::vector<physics::EffectPtr> e;
  e.push_back(physics::make_neo_hookean(500, 0.49));
  e.push_back(physics::make_dirichlet("clamp", clamp.facets()));
  e.push_back(std::move(pressure));
  physics::Problem pb(PETSC_COMM_WORLD, m, std::move(e), hstest::degree(2));
  core::VecH u = pb.create_vector();
  HS_PETSC(VecZeroEntries(u));
  return pb.resultants(u, 1.0).applied_force;
}

}  // namespace

TEST_CASE("A pressure on the organ surface has the resultant -p sum A_f N_f of its region", "[mpi][loads]") {
  const physics::Region clamp = physics::Region::box({-3, -3, -3}, {-0.6, 3, 3});  // the left lobe's tip
  const physics::Region top = physics::Region::box({-3, -3, 0.2}, {3, 3, 3});       // the domed upper side
  geometry::Boundary b;
  mesh::MeshData m;
  Vec3 region{}, clamped{}, closed{};
  double area = 0;
  if (core::rank(PETSC_COMM_WORLD) == 0) {
    b = organ_surface();
    mesh::BoundaryMeshOptions o;
    o.h = 0.3;
    m = mesh::mesh_boundary(b, o);
    region = area_vector(b, top.facets(), clamp.facets());
    clamped = area_vector(b, clamp.facets());
    closed = area_vector(b, {});
    for (int k = 0; k < 3; ++k) area = std::max(area, std::abs(region[k]));
  }
  for (Vec3* v : {&region, &clamped, &closed}) MPI_Bcast(v->data(), 3, MPI_DOUBLE, 0, PETSC_COMM_WORLD);
  MPI_Bcast(&area, 1, MPI_DOUBLE, 0, PETSC_COMM_WORLD);
  INFO("region area vector " << region[0] << ", " << region[1] << ", " << region[2]);
  REQUIRE(region[2] > 0.5);  // the upper side: a sizeable area facing +z
  REQUIRE(clamped[0] < -0.05);
  for (double c : closed) CHECK(std::abs(c) < 1e-12);  // a closed surface

  const double p = 3.0, q = 2.0;
  const Vec3 on_region = applied_force(m, clamp, physics::make_pressure(p, top, 3));
  const Vec3 on_free = applied_force(m, clamp, physics::make_pressure(q, physics::Region(), 3));
  for (int k = 0; k < 3; ++k) {
    CHECK(on_region[k] == Approx(-p * region[k]).epsilon(1e-12).margin(1e-12 * p * area));
    CHECK(on_free[k] == Approx(q * clamped[k]).epsilon(1e-12).margin(1e-12 * q * area));  // -q (0 - clamped)
  }
  CHECK(on_region[2] < 0);  // pushes the upper side down, into the body
}
