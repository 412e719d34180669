// A dataset scene's draws are pure functions of (seed, shape id, load id, effect, key): per
// shape the same for every load case, per load case not; in the distribution's range.
#include <catch2/catch.hpp>

#include <set>
#include <string>
#include <utility>
#include <vector>

#include "hypershape/config/dataset.hpp"
#include "hypershape/factory/dataset_scene.hpp"
#include "hypershape/factory/load_cases.hpp"
#include "hypershape/factory/shape_pipeline.hpp"
#include "hypershape/physics/problem.hpp"

using namespace hypershape;

TEST_CASE("drawn parameters: per shape, per load case, in range, reproducible", "[factory][scene]") {
  const auto c = config::parse_dataset_text(R"(preset: random2d
shapes: {count: 4}
effects:
  neo_hookean: {E: {log_uniform: [100, 1000]}, nu: 0.49}
  dirichlet_patch: {radius: {uniform: [0.3, 0.5]}}
  gaussian_traction: [{gamma: 0.2}, {gamma: {uniform: [0.1, 0.3], sample: load}}]
)", "<test>");
  std::set<double> E, gammas;
  for (std::int64_t s = 0; s < 4; ++s) {
    const auto first = factory::drawn_values(c, s, 0);
    REQUIRE(first.size() == 3);
    CHECK(first[0].name == "neo_hookean/E");
    CHECK(first[2].name == "gaussian_traction.1/gamma");
    CHECK(first[2].per_load);
    E.insert(first[0].value);
    CHECK((first[0].value >= 100 && first[0].value <= 1000));
    const double r = factory::shape_config(c, s).dirichlet_radius;
    CHECK(r == first[1].value);
    CHECK((r >= 0.3 && r <= 0.5));
    for (int l = 0; l < 5; ++l) {
      const auto v = factory::drawn_values(c, s, l);
      CHECK(v[0].value == first[0].value);  // per shape
      gammas.insert(v[2].value);
      CHECK((v[2].value >= 0.1 && v[2].value <= 0.3));
      CHECK(factory::drawn_values(c, s, l)[2].value == v[2].value);  // reproducible
    }
  }
  CHECK(E.size() == 4);
  CHECK(gammas.size() == 20);
  CHECK(factory::n_tractions(c) == 2);
}

TEST_CASE("mesh.quadrature reaches the space: P2 at exactness 2 has 3 points per triangle, else 6",
          "[factory][scene]") {
  for (const auto& [line, n_qp] : std::vector<std::pair<std::string, int>>{{"", 6}, {"mesh: {quadrature: 2}\n", 3}}) {
    const auto c = config::parse_dataset_text("preset: random2d\nshapes: {count: 1}\nloads: {count: 1}\n" + line, "<test>");
    const auto shape = factory::make_shape(c.shapes, std::nullopt, c.seed, 0);
    const auto loads = factory::draw_load_cases(shape, c.loads, c.seed);
    const auto sp = factory::make_shape_problem(PETSC_COMM_SELF, c, shape, loads[0]);
    CHECK(sp.problem->space().degree() == 2);
    CHECK(sp.problem->space().n_qp() == n_qp);
  }
}
