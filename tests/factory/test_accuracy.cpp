// Datasets asked for by accuracy (issue 19): the config block, the ladder and its prediction,
// and refine_shape (the shape on its mesh refined uniformly: same polygon/surface, boundary point i
// still mesh vertex i, the Dirichlet facets' children exactly the refined facets in the patch).
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "hypershape/config/dataset.hpp"
#include "hypershape/core/input_error.hpp"
#include "hypershape/factory/accuracy.hpp"
#include "hypershape/factory/dataset_scene.hpp"
#include "hypershape/geometry/surface_remesh.hpp"
#include "hypershape/mesh/refine.hpp"

using namespace hypershape;

namespace {

const std::string head = "preset: random2d_p1\nseed: 5\nshapes: {count: 3, h: 0.08}\nloads: {count: 2}\n";

std::string message(const std::string& text) {
  try {
    config::parse_dataset_text(text, "<test>");
  } catch (const core::InputError& e) {
    return e.what();
  }
  return "accepted";
}

/// Signed area (2D) or volume x 6 (3D) of every cell, summed; and whether all are positive.
std::pair<double, bool> mesh_measure(const mesh::MeshData& m) {
  const int d = m.dim, nv = d + 1;
  double total = 0;
  bool positive = true;
  for (std::int64_t c = 0; c < m.n_cells(); ++c) {
    const int* v = &m.cells[std::size_t(c * nv)];
    auto x = [&](int a, int k) { return m.coords[std::size_t(v[a] * d + k)] - m.coords[std::size_t(v[0] * d + k)]; };
    const double s = d == 2 ? x(1, 0) * x(2, 1) - x(1, 1) * x(2, 0)
                            : x(1, 0) * (x(2, 1) * x(3, 2) - x(2, 2) * x(3, 1)) -
                                  x(1, 1) * (x(2, 0) * x(3, 2) - x(2, 2) * x(3, 0)) +
                                  x(1, 2) * (x(2, 0) * x(3, 1) - x(2, 1) * x(3, 0));
    total += std::abs(s);
    positive = positive && (s > 0) == (d == 2);  // PETSc: CCW triangles, negative triple product tets
  }
  return {total, positive};
}

/// The boundary's facets are faces of the mesh's cells, and its points are the mesh's first vertices.
void check_boundary_on_mesh(const factory::ShapeSample& s) {
  const int d = s.mesh.dim, nv = d + 1;
  for (std::int64_t i = 0; i < s.boundary.n_points(); ++i)
    for (int k = 0; k < d; ++k) REQUIRE(s.boundary.point(i)[std::size_t(k)] == s.mesh.coords[std::size_t(i * d + k)]);
  std::set<std::vector<int>> faces;
  for (std::int64_t c = 0; c < s.mesh.n_cells(); ++c)
    for (int skip = 0; skip < nv; ++skip) {
      std::vector<int> f;
      for (int a = 0; a < nv; ++a)
        if (a != skip) f.push_back(s.mesh.cells[std::size_t(c * nv + a)]);
      std::sort(f.begin(), f.end());
      faces.insert(f);
    }
  for (std::int64_t f = 0; f < s.boundary.n_facets(); ++f) {
    std::vector<int> v(s.boundary.facet(f).begin(), s.boundary.facet(f).end());
    std::sort(v.begin(), v.end());
    REQUIRE(faces.count(v) == 1);
  }
}

}  // namespace

TEST_CASE("accuracy: is parsed, validated, implies the estimate and joins the identity only when given",
          "[factory][accuracy]") {
  const auto plain = config::parse_dataset_text(head, "<test>");
  const auto acc = config::parse_dataset_text(head + "accuracy: {rel_l2: 0.01}\n", "<test>");
  CHECK(!plain.accuracy.enabled());
  CHECK(acc.accuracy.rel_l2 == 0.01);
  CHECK(acc.accuracy.max_level == 2);
  CHECK(acc.representations.error_estimate);
  CHECK(config::canonical_text(plain).find("accuracy") == std::string::npos);
  CHECK(config::canonical_text(acc) != config::canonical_text(plain));
  CHECK(config::canonical_text(config::parse_dataset_text(head + "accuracy: {rel_l2: 0.003}\n", "<test>")) !=
        config::canonical_text(acc));
  // start: rest (the default; the identity as before the key) or coarse, a different dataset.
  CHECK(!acc.accuracy.start_from_coarse);
  const auto coarse = config::parse_dataset_text(head + "accuracy: {rel_l2: 0.01, start: coarse}\n", "<test>");
  CHECK(coarse.accuracy.start_from_coarse);
  CHECK(config::canonical_text(coarse) != config::canonical_text(acc));
  CHECK(config::canonical_text(config::parse_dataset_text(head + "accuracy: {rel_l2: 0.01, start: rest}\n", "<test>")) ==
        config::canonical_text(acc));
  CHECK_THAT(config::canonical_text(acc), Catch::Contains("accuracy: [0.01, 2, 0]\n"));
  CHECK_THAT(message(head + "accuracy: {rel_l2: 0.01, start: fine}\n"), Catch::Contains("accuracy.start"));
  // resolve_newton_budget: the re-solves' Newton budget (default: the solver's), in the identity only when given.
  CHECK(acc.accuracy.resolve_newton_budget == 0);
  const auto capped = config::parse_dataset_text(head + "accuracy: {rel_l2: 0.01, resolve_newton_budget: 80}\n", "<test>");
  CHECK(capped.accuracy.resolve_newton_budget == 80);
  CHECK_THAT(config::canonical_text(capped), Catch::Contains("accuracy: [0.01, 2, 0, budget 80]\n"));
  CHECK_THAT(message(head + "accuracy: {rel_l2: 0.01, resolve_newton_budget: 0}\n"),
             Catch::Contains("accuracy.resolve_newton_budget"));
  CHECK_THAT(message(head + "accuracy: {rel_l2: 0.01, resolve_newton_budget: 1.5}\n"),
             Catch::Contains("accuracy.resolve_newton_budget"));
  // resolve_retries: true (the default: the solver's retry from rest and P1 start in re-solves too)
  // or false (one try), in the identity only when false.
  CHECK(acc.accuracy.resolve_retries);
  const auto once = config::parse_dataset_text(head + "accuracy: {rel_l2: 0.01, resolve_retries: false}\n", "<test>");
  CHECK(!once.accuracy.resolve_retries);
  CHECK_THAT(config::canonical_text(once), Catch::Contains("accuracy: [0.01, 2, 0, one try]\n"));
  CHECK(config::canonical_text(config::parse_dataset_text(head + "accuracy: {rel_l2: 0.01, resolve_retries: true}\n",
                                                          "<test>")) == config::canonical_text(acc));
  CHECK_THAT(message(head + "accuracy: {rel_l2: 0.01, resolve_retries: 2}\n"), Catch::Contains("accuracy.resolve_retries"));
  CHECK_THAT(message(head + "accuracy: {rel_l2: 0}\n"), Catch::Contains("accuracy.rel_l2"));
  CHECK_THAT(message(head + "accuracy: {rel_l2: 1}\n"), Catch::Contains("accuracy.rel_l2"));
  CHECK_THAT(message(head + "accuracy: {rel_l2: 0.01, bound: 2}\n"), Catch::Contains("accuracy.bound"));
  CHECK_THAT(message(head + "accuracy: {rel_l2: 0.01, exceed_share: 0.9}\n"), Catch::Contains("accuracy.exceed_share"));
  CHECK_THAT(message(head + "accuracy: 0.01\n"), Catch::Contains("accuracy"));
  CHECK_THAT(message(head + "representations: {error_estimate: false}\naccuracy: {rel_l2: 0.01}\n"),
             Catch::Contains("representations.error_estimate"));
}

TEST_CASE("The accuracy ladder and its prediction", "[factory][accuracy]") {
  auto c = config::parse_dataset_text(head + "accuracy: {rel_l2: 0.01, max_level: 3}\n", "<test>");
  const auto l0 = factory::accuracy_level(c, 0), l1 = factory::accuracy_level(c, 1), l3 = factory::accuracy_level(c, 3);
  CHECK((l0.degree == 1 && l0.refinements == 0 && l0.h == 0.08));
  CHECK((l1.degree == 2 && l1.refinements == 0));
  CHECK((l3.degree == 2 && l3.refinements == 2 && l3.h == 0.02));
  CHECK(factory::predicted_reduction(l0, l3) == 40.0);
  CHECK(factory::next_accuracy_level(c, 0, 0.05) == 1);   // 0.05 / 10 meets 0.01
  CHECK(factory::next_accuracy_level(c, 0, 0.15) == 2);   // / 20
  CHECK(factory::next_accuracy_level(c, 0, 5.0) == 3);    // capped at max_level
  CHECK(factory::next_accuracy_level(c, 1, 0.011) == 2);  // always at least one up
  CHECK(factory::next_accuracy_level(c, 1, -1) == 2);     // no estimate: one up
  c.degree = 2;
  CHECK(factory::accuracy_level(c, 1).refinements == 1);
}

TEST_CASE("A label no level is predicted to bring under the bound does not climb", "[factory][accuracy]") {
  // P1 ladder to level 3 (P2, two refinements): the last level is predicted 40x below level 0,
  // 4x below level 1, 2x below level 2.
  const auto c = config::parse_dataset_text(head + "accuracy: {rel_l2: 0.01, max_level: 3}\n", "<test>");
  CHECK(factory::curable(c, 0, 0.39));      // 0.39 / 40 meets 0.01
  CHECK_FALSE(factory::curable(c, 0, 0.41));
  CHECK(factory::curable(c, 1, 0.04));      // / 4
  CHECK_FALSE(factory::curable(c, 1, 0.05));
  CHECK(factory::curable(c, 2, 0.02));      // / 2
  CHECK_FALSE(factory::curable(c, 2, 0.021));
  CHECK(factory::curable(c, 0, -1));        // no estimate: worth a level up
  CHECK(factory::curable(c, 2, -2));
  CHECK_FALSE(factory::curable(c, 3, -1));  // nothing above the last level
  CHECK_FALSE(factory::curable(c, 3, 0.011));
}

TEST_CASE("The load-case ladder: who climbs, to which level, and the fall-back after a failed jump",
          "[factory][accuracy]") {
  // P1 ladder to level 3; bound 0.01. Level 0 -> 1 is predicted 10x, -> 2 20x, -> 3 40x. Re-solves
  // from rest (start: rest) jump to the lowest level predicted to meet the bound.
  const auto c = config::parse_dataset_text(head + "accuracy: {rel_l2: 0.01, max_level: 3, start: rest}\n", "<test>");
  factory::LoadLadder ladder(c, 5);
  std::vector<int> loads;
  CHECK(ladder.record(0, 0, true, 0.005));  // meets the bound
  CHECK(ladder.record(1, 0, true, 0.05));   // -> 1
  CHECK(ladder.record(2, 0, true, 0.15));   // -> 2 (skips 1)
  CHECK(ladder.record(3, 0, true, 0.5));    // incurable: 0.5 / 40 misses
  CHECK(ladder.record(4, 0, false, -1));    // failed at level 0: no label, no climb
  CHECK(ladder.waiting(0) == -1);
  CHECK(ladder.waiting(3) == -1);
  CHECK(ladder.waiting(4) == -1);
  REQUIRE(ladder.next(loads) == 1);
  CHECK(loads == std::vector<int>{1});
  CHECK(ladder.record(1, 1, true, 0.008));  // kept, meets it
  CHECK(ladder.waiting(1) == -1);
  REQUIRE(ladder.next(loads) == 2);
  CHECK(loads == std::vector<int>{2});
  // The jump fails: the label of level 0 stays, and the level it skipped is tried.
  CHECK_FALSE(ladder.record(2, 2, false, -1));
  CHECK(ladder.kept(2) == 0);
  CHECK(ladder.falls_back(2));
  CHECK_FALSE(ladder.falls_back(1));
  REQUIRE(ladder.next(loads) == 1);
  CHECK(loads == std::vector<int>{2});
  // At level 1 it estimates lower but still misses: it climbs past the failed level 2 to 3.
  CHECK(ladder.record(2, 1, true, 0.012));
  CHECK(ladder.kept(2) == 1);
  CHECK_FALSE(ladder.falls_back(2));  // climbs on, past the level that failed
  REQUIRE(ladder.next(loads) == 3);
  CHECK(loads == std::vector<int>{2});
  CHECK_FALSE(ladder.record(2, 3, true, 0.013));  // no lower: level 1's label stays; nothing skipped
  CHECK(ladder.next(loads) == -1);
  CHECK(ladder.kept_levels() == std::vector<int>{0, 1, 1, 0, 0});
  CHECK(ladder.highest_tried(2) == 3);
  CHECK(ladder.highest_tried(1) == 1);
  CHECK(ladder.highest_tried(3) == 0);
}

TEST_CASE("The load-case ladder: a failed step to the next level ends the climb; the share allowed above stays",
          "[factory][accuracy]") {
  const auto c = config::parse_dataset_text(head + "accuracy: {rel_l2: 0.01, max_level: 3, start: rest}\n", "<test>");
  factory::LoadLadder ladder(c, 2);
  std::vector<int> loads;
  ladder.record(0, 0, true, 0.05);
  ladder.record(1, 0, true, -2);  // converged, no estimate: one level up
  REQUIRE(ladder.next(loads) == 1);
  CHECK(loads == std::vector<int>{0, 1});
  CHECK_FALSE(ladder.record(0, 1, true, 0.06));  // no lower, and not curable from level 1 (0.06 / 4): stays at 0
  CHECK(ladder.waiting(0) == -1);
  CHECK(ladder.record(1, 1, true, 0.3));  // any estimate beats none; 0.3 / 4 misses: stays
  CHECK(ladder.waiting(1) == -1);
  CHECK(ladder.next(loads) == -1);
  CHECK(loads.empty());
  CHECK(ladder.kept_levels() == std::vector<int>{0, 1});

  // exceed_share 0.25 of 4 load cases: one may stay above the bound, so one alone does not climb.
  const auto s = config::parse_dataset_text(head + "accuracy: {rel_l2: 0.01, max_level: 3, exceed_share: 0.25}\n",
                                            "<test>");
  factory::LoadLadder shared(s, 4);
  for (int L = 0; L < 4; ++L) shared.record(L, 0, true, L == 2 ? 0.05 : 0.001);
  CHECK(shared.waiting(2) == 1);
  CHECK(shared.next(loads) == -1);
  shared.record(3, 0, true, 0.02);  // recorded again (a test only): two wait, so both climb
  CHECK(shared.next(loads) == 1);
  CHECK(loads == std::vector<int>{2, 3});
}

TEST_CASE("The load-case ladder: a converged re-solve not kept climbs on from its own estimate; a failed one stops",
          "[factory][accuracy]") {
  const auto c = config::parse_dataset_text(head + "accuracy: {rel_l2: 0.01, max_level: 3, start: rest}\n", "<test>");
  factory::LoadLadder ladder(c, 3);
  std::vector<int> loads;
  for (int L = 0; L < 3; ++L) ladder.record(L, 0, true, 0.02);  // 0.02 / 10: all wait for level 1
  REQUIRE(ladder.next(loads) == 1);
  CHECK_FALSE(ladder.record(0, 1, true, 0.025));  // no lower; from level 1, 0.025 / 4 meets: on to 3 (/2 misses)
  CHECK(ladder.waiting(0) == 3);
  CHECK_FALSE(ladder.falls_back(0));
  CHECK_FALSE(ladder.record(1, 1, true, -2));  // converged, no estimate: one level up
  CHECK(ladder.waiting(1) == 2);
  CHECK_FALSE(ladder.record(2, 1, false, -1));  // failed, nothing skipped: the climb ends
  CHECK(ladder.waiting(2) == -1);
  REQUIRE(ladder.next(loads) == 2);
  CHECK(loads == std::vector<int>{1});
  CHECK(ladder.record(1, 2, true, 0.004));  // lower than level 0's 0.02: kept
  REQUIRE(ladder.next(loads) == 3);
  CHECK(loads == std::vector<int>{0});
  CHECK(ladder.record(0, 3, true, 0.008));
  CHECK(ladder.next(loads) == -1);
  CHECK(ladder.kept_levels() == std::vector<int>{3, 2, 0});
}

TEST_CASE("The load-case ladder with start: coarse climbs one level at a time, each start warm", "[factory][accuracy]") {
  // The same first records as the jump test above: the label predicted to need level 2 (0.15 / 20)
  // goes to level 1 first; what the prediction still decides is whether a label climbs at all.
  const auto c = config::parse_dataset_text(head + "accuracy: {rel_l2: 0.01, max_level: 3, start: coarse}\n", "<test>");
  REQUIRE(c.accuracy.start_from_coarse);
  factory::LoadLadder ladder(c, 3);
  std::vector<int> loads;
  ladder.record(0, 0, true, 0.05);
  ladder.record(1, 0, true, 0.15);
  ladder.record(2, 0, true, 0.5);  // incurable (0.5 / 40): no climb
  CHECK(ladder.waiting(1) == 1);
  CHECK(ladder.waiting(2) == -1);
  REQUIRE(ladder.next(loads) == 1);
  CHECK(loads == std::vector<int>{0, 1});
  CHECK(ladder.record(0, 1, true, 0.008));
  CHECK(ladder.record(1, 1, true, 0.03));   // kept, still above: one level up, not to 3 (0.03 / 4 would meet)
  CHECK(ladder.waiting(1) == 2);
  REQUIRE(ladder.next(loads) == 2);
  CHECK(ladder.record(1, 2, true, 0.012));  // kept, above: on to 3
  REQUIRE(ladder.next(loads) == 3);
  CHECK_FALSE(ladder.record(1, 3, false, -1));  // failed: level 2's label stays; nothing skipped, no fall-back
  CHECK_FALSE(ladder.falls_back(1));
  CHECK(ladder.next(loads) == -1);
  CHECK(ladder.kept_levels() == std::vector<int>{1, 2, 0});
}

TEST_CASE("grade_shape keeps the polygon and its patch and grades the mesh towards the clamp ends",
          "[factory][accuracy]") {
  const auto c = config::parse_dataset_text(head, "<test>");
  const auto s = factory::make_shape(factory::shape_config(c, 1), std::nullopt, c.seed, 1);
  const double h = 0.08, end = h / 32;
  const auto g = factory::grade_shape(s, h, end, 0.3);
  const auto [area, positive] = mesh_measure(g.mesh);
  CHECK(positive);
  CHECK(area == Approx(mesh_measure(s.mesh).first).epsilon(1e-12));
  check_boundary_on_mesh(g);
  for (std::int64_t f = 0; f + 1 < g.boundary.n_facets(); ++f) CHECK(g.boundary.facet(f)[1] == g.boundary.facet(f + 1)[0]);
  // Every drawn point is kept, in order; the points added lie on the drawn segment they split.
  std::int64_t j = 0;
  for (std::int64_t i = 0; i < s.boundary.n_points(); ++i) {
    const auto p = s.boundary.point(i), q = s.boundary.point((i + 1) % s.boundary.n_points());
    while (g.boundary.point(j)[0] != p[0] || g.boundary.point(j)[1] != p[1]) {
      REQUIRE(j > 0);  // an added point: on the previous segment
      ++j;
      REQUIRE(j < g.boundary.n_points());
    }
    for (++j; j < g.boundary.n_points() && (g.boundary.point(j)[0] != q[0] || g.boundary.point(j)[1] != q[1]); ++j) {
      const auto x = g.boundary.point(j);
      const double cross = (q[0] - p[0]) * (x[1] - p[1]) - (q[1] - p[1]) * (x[0] - p[0]);
      CHECK(std::abs(cross) < 1e-14);
      const double t = ((x[0] - p[0]) * (q[0] - p[0]) + (x[1] - p[1]) * (q[1] - p[1])) /
                       ((q[0] - p[0]) * (q[0] - p[0]) + (q[1] - p[1]) * (q[1] - p[1]));
      CHECK((t > 0 && t < 1));
    }
  }
  // The patch: the same facets' union (the children of the drawn patch's facets), the same ends.
  CHECK(g.dirichlet_facets == geometry::facets_in_ball(g.boundary, s.dirichlet_center, s.dirichlet_radius));
  double patch = 0, patch_drawn = 0;
  for (int f : g.dirichlet_facets) patch += geometry::facet_measure(g.boundary, f);
  for (int f : s.dirichlet_facets) patch_drawn += geometry::facet_measure(s.boundary, f);
  CHECK(patch == Approx(patch_drawn).epsilon(1e-12));
  const auto ends = factory::clamp_ends(g);
  REQUIRE(ends == factory::clamp_ends(s));
  REQUIRE(ends.size() == 2);
  // Graded: the facets at an end are about `end` long; points are added only where the wanted size
  // (end + 0.3 x distance to the nearest end) is below the drawn facets' longest.
  double longest = 0;
  std::set<std::array<double, 2>> drawn;
  for (std::int64_t f = 0; f < s.boundary.n_facets(); ++f) longest = std::max(longest, geometry::facet_measure(s.boundary, f));
  for (std::int64_t i = 0; i < s.boundary.n_points(); ++i) drawn.insert({s.boundary.point(i)[0], s.boundary.point(i)[1]});
  int added = 0;
  for (std::int64_t f = 0; f < g.boundary.n_facets(); ++f) {
    const auto a = g.boundary.point(g.boundary.facet(f)[0]);
    double d = 1e300;
    for (const auto& e : ends) d = std::min(d, std::hypot(a[0] - e[0], a[1] - e[1]));
    if (d == 0) CHECK(geometry::facet_measure(g.boundary, f) < 1.5 * end);
    if (!drawn.contains({a[0], a[1]})) {
      ++added;
      CHECK(end + 0.3 * d < 1.5 * longest);
    }
  }
  CHECK(added > 10);
  CHECK(g.mesh.n_vertices() > 0.9 * double(s.mesh.n_vertices()));
  CHECK(g.mesh.n_vertices() < 1.5 * double(s.mesh.n_vertices()));
  // Deterministic: the same input, the same mesh.
  CHECK(factory::grade_shape(s, h, end, 0.3).mesh.coords == g.mesh.coords);
  // 2D only: a 3D shape is refused before any meshing.
  factory::ShapeSample s3;
  s3.mesh.dim = 3;
  CHECK_THROWS_AS(factory::grade_shape(s3, h, end, 0.3), std::invalid_argument);
}

TEST_CASE("refine_shape keeps the shape, its patch and the boundary-first numbering", "[factory][accuracy]") {
  const auto c = config::parse_dataset_text(head, "<test>");
  const auto s = factory::make_shape(factory::shape_config(c, 1), std::nullopt, c.seed, 1);
  const auto r = factory::refine_shape(s);
  CHECK(r.mesh.n_cells() == 4 * s.mesh.n_cells());
  CHECK(r.boundary.n_facets() == 2 * s.boundary.n_facets());
  CHECK(r.boundary.n_points() == 2 * s.boundary.n_points());
  const auto [area, positive] = mesh_measure(r.mesh);
  CHECK(positive);
  CHECK(area == Approx(mesh_measure(s.mesh).first).epsilon(1e-12));
  check_boundary_on_mesh(r);
  // 2D: the polygon in order, counter-clockwise (facet f ends where facet f + 1 starts).
  for (std::int64_t f = 0; f + 1 < r.boundary.n_facets(); ++f) CHECK(r.boundary.facet(f)[1] == r.boundary.facet(f + 1)[0]);
  CHECK(r.dirichlet_facets == geometry::facets_in_ball(r.boundary, s.dirichlet_center, s.dirichlet_radius));
  const auto rr = factory::refine_shape(r);
  check_boundary_on_mesh(rr);
  CHECK(rr.dirichlet_facets.size() == 4 * s.dirichlet_facets.size());
}

TEST_CASE("node_permutation matches the refined mesh's nodes in refine_shape's numbering, bit for bit", "[factory][accuracy]") {
  // The estimator refines the shape's mesh with mesh::refine_uniform; the ladder's next level is
  // refine_shape's (the same mesh, boundary first): a fine state of the one starts the other.
  const auto c = config::parse_dataset_text(head, "<test>");
  const auto s = factory::make_shape(factory::shape_config(c, 1), std::nullopt, c.seed, 1);
  const auto u = mesh::refine_uniform(s.mesh).mesh;
  const auto r = factory::refine_shape(s).mesh;
  const auto p = factory::node_permutation(u.coords, r.coords, 2);
  REQUIRE(p.size() == std::size_t(r.n_vertices()));
  CHECK(std::set<std::int64_t>(p.begin(), p.end()).size() == p.size());
  for (std::size_t j = 0; j < p.size(); ++j)
    for (std::size_t k = 0; k < 2; ++k) CHECK(r.coords[j * 2 + k] == u.coords[std::size_t(p[j]) * 2 + k]);
  bool renumbered = false;  // refine_shape numbers the boundary first: not the identity
  for (std::size_t j = 0; j < p.size(); ++j) renumbered = renumbered || p[j] != std::int64_t(j);
  CHECK(renumbered);
  auto moved = r.coords;
  moved[7] = std::nextafter(moved[7], 1e9);  // one node off by one ulp: not the same node set
  CHECK(factory::node_permutation(u.coords, moved, 2).empty());
  CHECK(factory::node_permutation(u.coords, std::vector<double>(r.coords.begin(), r.coords.end() - 2), 2).empty());
}

TEST_CASE("refine_shape on a tetrahedron: outward facets split in four", "[factory][accuracy]") {
  factory::ShapeSample s;
  s.mesh.dim = 3;
  s.mesh.coords = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  s.mesh.cells = {0, 2, 1, 3};  // negative triple product (PETSc's orientation)
  s.boundary.dim = 3;
  s.boundary.points = s.mesh.coords;
  s.boundary.facets = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};  // outward
  s.dirichlet_facets = {2};
  const auto r = factory::refine_shape(s);
  CHECK(r.mesh.n_cells() == 8);
  CHECK(r.boundary.n_facets() == 16);
  CHECK(r.boundary.n_points() == 10);  // every node of a refined tetrahedron is on its surface
  CHECK(mesh_measure(r.mesh).second);
  CHECK(mesh_measure(r.mesh).first == Approx(1.0));
  check_boundary_on_mesh(r);
  CHECK(r.dirichlet_facets == std::vector<int>{8, 9, 10, 11});
  for (std::int64_t f = 0; f < r.boundary.n_facets(); ++f) {  // outward: the normal points away from the centroid
    const auto v = r.boundary.facet(f);
    std::array<std::array<double, 3>, 3> x;
    for (int a = 0; a < 3; ++a)
      for (int k = 0; k < 3; ++k) x[std::size_t(a)][std::size_t(k)] = r.boundary.point(v[std::size_t(a)])[std::size_t(k)];
    double e1[3], e2[3], n[3], m[3];
    for (int k = 0; k < 3; ++k) e1[k] = x[1][k] - x[0][k], e2[k] = x[2][k] - x[0][k], m[k] = x[0][k] - 0.25;
    n[0] = e1[1] * e2[2] - e1[2] * e2[1], n[1] = e1[2] * e2[0] - e1[0] * e2[2], n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    CHECK(n[0] * m[0] + n[1] * m[1] + n[2] * m[2] > 0);
  }
}
