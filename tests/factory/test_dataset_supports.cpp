// Several Dirichlet supports in a dataset (issue 18): the drawn dirichlet_patch plus fixed
// `dirichlet` regions. A region's facets join the shape's Dirichlet facets (so the stored mask,
// distance and load placements see them), the draw stays a pure function of (seed, shape id),
// the solve holds every node of every support at u = 0, and bad input names its key.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <set>
#include <string>

#include "hypershape/config/dataset.hpp"
#include "hypershape/core/input_error.hpp"
#include "hypershape/factory/dataset_scene.hpp"
#include "hypershape/factory/load_cases.hpp"
#include "hypershape/solver/nonlinear.hpp"

using namespace hypershape;

namespace {

// The mesh as drawn (mesh.rim 0): a graded one splits facets at the regions' ends, where the
// facet test below, read on the drawn polygon, decides membership.
const std::string head = "preset: random2d\nseed: 5\nshapes: {count: 3, h: 0.08}\nloads: {count: 2}\nmesh: {rim: 0}\n";
const std::string regions = "  dirichlet:\n    - {box: [-3, -3, -0.7, 3]}\n    - {center: [0, -1.5], radius: 0.8}\n";

config::DatasetConfig parse(const std::string& effects) {
  return config::parse_dataset_text(head + "effects:\n  neo_hookean: {E: 500, nu: 0.49}\n" + effects +
                                         "  gaussian_traction: {gamma: 0.2}\n",
                                     "<test>");
}

bool in_box(const double* x) { return x[0] <= -0.7 + 1e-9; }
bool in_ball(const double* x) { return std::hypot(x[0], x[1] + 1.5) <= 0.8 + 1e-9; }
bool in_patch(const factory::ShapeSample& s, const double* x) {
  return std::hypot(x[0] - s.dirichlet_center[0], x[1] - s.dirichlet_center[1]) <= s.dirichlet_radius + 1e-9;
}

/// Whether every vertex of facet f satisfies `in`.
template <class In>
bool facet_in(const geometry::Boundary& b, int f, In in) {
  for (int v : b.facet(f))
    if (!in(b.point(v).data())) return false;
  return true;
}

std::string message(const std::string& effects) {
  try {
    parse(effects);
  } catch (const core::InputError& e) {
    return e.what();
  }
  return "accepted";
}

}  // namespace

TEST_CASE("A dataset takes fixed Dirichlet regions beside its drawn patch", "[factory][supports]") {
  const auto c = parse("  dirichlet_patch: {radius: 0.3}\n" + regions);
  REQUIRE(c.shapes.fixed_supports.size() == 2);
  const auto plain = parse("  dirichlet_patch: {radius: 0.3}\n");
  int n_same = 0;  // shapes drawn at the same attempt with and without the regions
  for (std::int64_t id = 0; id < 3; ++id) {
    const auto s = factory::make_shape(factory::shape_config(c, id), std::nullopt, c.seed, id);
    const auto again = factory::make_shape(factory::shape_config(c, id), std::nullopt, c.seed, id);
    CHECK(again.dirichlet_facets == s.dirichlet_facets);  // a pure function of (seed, shape id)
    // Exactly the facets in the patch or in a region, and each region holds some.
    const std::set<int> fixed(s.dirichlet_facets.begin(), s.dirichlet_facets.end());
    int n_box = 0, n_ball = 0;
    for (int f = 0; f < int(s.boundary.n_facets()); ++f) {
      const bool box = facet_in(s.boundary, f, in_box), ball = facet_in(s.boundary, f, in_ball);
      const bool patch = facet_in(s.boundary, f, [&](const double* x) { return in_patch(s, x); });
      n_box += box, n_ball += ball;
      CHECK(fixed.count(f) == std::size_t(box || ball || patch));
    }
    CHECK(n_box > 0);
    CHECK(n_ball > 0);
    // The patch alone (the paper's scene) draws the same shape when no redraw was needed.
    const auto p = factory::make_shape(factory::shape_config(plain, id), std::nullopt, plain.seed, id);
    if (p.attempt == s.attempt) {
      ++n_same;
      CHECK(p.boundary.points == s.boundary.points);
      CHECK(p.dirichlet_center == s.dirichlet_center);
      CHECK(p.dirichlet_facets.size() < s.dirichlet_facets.size());
    }
  }
  CHECK(n_same == 3);  // measured: every shape reaches both regions at its first attempt
}

TEST_CASE("Fixed regions alone: no drawn patch, u = 0 on every region after the solve", "[factory][supports]") {
  const auto c = parse(regions);
  CHECK(c.shapes.dirichlet_radius == 0.0);
  const auto s = factory::make_shape(factory::shape_config(c, 1), std::nullopt, c.seed, 1);
  REQUIRE_FALSE(s.dirichlet_facets.empty());
  for (int f : s.dirichlet_facets) CHECK((facet_in(s.boundary, f, in_box) || facet_in(s.boundary, f, in_ball)));
  const auto cases = factory::draw_load_cases(s, c.loads, c.seed, factory::n_tractions(c));
  auto sp = factory::make_shape_problem(PETSC_COMM_WORLD, c, s, cases[0]);
  solver::NonlinearSolver ns(*sp.problem, c.solver);
  const auto r = ns.solve_for_target(0.2);
  REQUIRE(r.converged);
  const physics::NodalField u = sp.problem->gather(ns.solution());
  if (core::rank(PETSC_COMM_WORLD) != 0) return;
  double held = 0, moved = 0;  // max |u| on the Dirichlet facets' vertices, and anywhere
  for (int f : s.dirichlet_facets)
    for (int v : s.boundary.facet(f)) held = std::max({held, std::abs(u.values[2 * std::size_t(v)]), std::abs(u.values[2 * std::size_t(v) + 1])});
  for (double x : u.values) moved = std::max(moved, std::abs(x));
  CHECK(held == 0.0);
  CHECK(moved > 0.1);
}

TEST_CASE("Bad Dirichlet supports in a dataset are refused naming the key", "[factory][supports][input]") {
  CHECK_THAT(message("  dirichlet_patch: [{radius: 0.3}, {radius: 0.2}]\n"),
             Catch::Contains("dirichlet_patch[1]") && Catch::Contains("at most one dirichlet_patch"));
  CHECK_THAT(message("  dirichlet: {box: [-3, -3, -0.7, 3], components: [0]}\n"),
             Catch::Contains("dirichlet.components") && Catch::Contains("every component"));
  CHECK_THAT(message("  dirichlet: {center: [0, -1.5], radius: {uniform: [0.5, 0.8]}}\n"),
             Catch::Contains("dirichlet.radius") && Catch::Contains("fixed region"));
  CHECK_THAT(message("  dirichlet: {box: [-3, -0.7, 3]}\n"), Catch::Contains("dirichlet.box"));
  CHECK_THAT(message("  dirichlet: {components: [0]}\n"), Catch::Contains("dirichlet"));
  CHECK_THAT(message("  spring: {stiffness: 10}\n"), Catch::Contains("needs a Dirichlet support"));
}

TEST_CASE("In 3D a fixed region's facets join the drawn patch's", "[factory][supports]") {
  auto parse3 = [](const std::string& extra) {
    return config::parse_dataset_text("preset: random3d\nseed: 3\nshapes: {count: 1, h: 0.2}\neffects:\n"
                                      "  neo_hookean: {E: 500, nu: 0.49}\n  dirichlet_patch: {radius: 0.4}\n" +
                                          extra + "  gaussian_traction: {gamma: 0.2}\n",
                                      "<test>");
  };
  const auto c = parse3("  dirichlet: {box: [-3, -3, -3, 3, 3, -0.7]}\n"), plain = parse3("");
  const auto s = factory::make_shape(factory::shape_config(c, 0), std::nullopt, c.seed, 0);
  const auto p = factory::make_shape(factory::shape_config(plain, 0), std::nullopt, plain.seed, 0);
  REQUIRE(p.attempt == s.attempt);  // measured: the region is reached at the first attempt
  REQUIRE(p.boundary.points == s.boundary.points);
  std::set<int> want(p.dirichlet_facets.begin(), p.dirichlet_facets.end());
  int n_region = 0;
  for (int f = 0; f < int(s.boundary.n_facets()); ++f)
    if (facet_in(s.boundary, f, [](const double* x) { return x[2] <= -0.7 + 1e-9; })) want.insert(f), ++n_region;
  CHECK(n_region > 0);
  CHECK(std::vector<int>(want.begin(), want.end()) == s.dirichlet_facets);
}
