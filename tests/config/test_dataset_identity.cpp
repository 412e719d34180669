// A dataset's identity is its meaning (config::canonical_text), not its text; and the YAML
// checks yaml-cpp lets through: a key given twice, a quoted string not closed on its line, a
// scalar where a mapping belongs, integers beyond 2^53.
#include <catch2/catch.hpp>

#include <string>

#include "hypershape/config/dataset.hpp"
#include "hypershape/core/input_error.hpp"

using namespace hypershape;

// Named for the unity build (HS_UNITY_BUILD): files of one batch share a scope.
namespace test_dataset_identity {
namespace {

const char* base = R"(preset: random2d
name: same
seed: 3
shapes: {count: 4, h: 0.1}
loads: {count: 3}
)";

std::string canonical(const std::string& text) {
  return config::canonical_text(config::parse_dataset_text(text, "test.yaml"));
}

std::string error_of(const std::string& text) {
  try {
    config::parse_dataset_text(text, "test.yaml");
  } catch (const core::InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("the same dataset reformatted, reordered or with defaults written out has one identity",
          "[config][identity]") {
  const std::string a = canonical(base);
  CHECK(canonical(R"(# a comment
loads:
  count: 3
  target: [0.1, 0.5]
shapes:
  h: 0.1
  count: 4
seed: 3
name: same
solver: {rtol: 1.0e-9, linear: auto, step_growth: 0, abandon_off_path: false, absolute_pivots: false, arc_length_rescue: false, retry_from_rest: true, predictor: second_order, corrector: chebyshev, local_relaxation: true}
petsc: {}
preset: random2d
)") == a);
  // the shorthand and the effects block it stands for
  CHECK(canonical(std::string(base) + "material: {E: 500, nu: 0.49}\n") == a);
  // PETSc options in any order
  CHECK(canonical(std::string(base) + "petsc: {pc_type: lu, ksp_type: preonly}\n") ==
        canonical(std::string(base) + "petsc: {ksp_type: preonly, pc_type: lu}\n"));
}

TEST_CASE("a different value is a different dataset", "[config][identity]") {
  const std::string a = canonical(base);
  for (const char* change : {"seed: 4\n", "loads: {count: 3, target: [0.1, 0.4]}\n", "material: {E: 501}\n",
                             "mesh: {degree: 1}\n", "mesh: {quadrature: 2}\n", "petsc: {pc_type: lu}\n", "output: {shard_size: 2}\n",
                             "solver: {linear: gamg}\n", "solver: {linear_auto_dofs: 1000}\n",
                             "solver: {abandon_off_path: true}\n", "solver: {absolute_pivots: true}\n",
                             "solver: {arc_length_rescue: true}\n",
                             "solver: {retry_from_rest: false}\n",
                             "solver: {step_growth: 2}\n", "solver: {predictor: tangent}\n",
                             "solver: {corrector: newton}\n", "solver: {local_relaxation: false}\n"}) {
    std::string t = base;
    const std::string key = std::string(change).substr(0, std::string(change).find(':') + 1);
    if (auto p = t.find(key); p != std::string::npos) t.erase(p, t.find('\n', p) - p + 1);
    CAPTURE(change);
    CHECK(canonical(t + change) != a);
  }
}

TEST_CASE("mesh.quadrature: in the identity only when given; refused below what the degree needs",
          "[config][identity]") {
  // The default written out is the same value but another identity only if given: older
  // datasets keep theirs (the canonical text has no quadrature line without the key).
  CHECK(canonical(base).find("quadrature") == std::string::npos);
  CHECK(config::parse_dataset_text(std::string(base) + "mesh: {quadrature: 2}\n", "t").quadrature == 2);
  CHECK_THAT(error_of(std::string(base) + "mesh: {quadrature: 1}\n"),
             Catch::Contains("mesh.quadrature: must be an integer in [2, 8]"));  // the preset is P2
  CHECK(error_of(std::string(base) + "mesh: {degree: 1, quadrature: 1}\n").empty());
  CHECK_THAT(error_of(std::string(base) + "mesh: {degree: 1, quadrature: 1}\naccuracy: {rel_l2: 0.01}\n"),
             Catch::Contains("mesh.quadrature: 1 with accuracy"));
  CHECK_THAT(error_of(std::string(base) + "mesh: {quadrature: 9}\n"), Catch::Contains("mesh.quadrature"));
}

TEST_CASE("YAML that yaml-cpp accepts silently is an input error naming the key", "[config][yaml]") {
  CHECK_THAT(error_of(std::string(base) + "seed: 5\n"), Catch::Contains("test.yaml: seed: given twice (line 6)"));
  CHECK_THAT(error_of("preset: random2d\nname: x\nseed: 1\nshapes: {count: 2, count: 3}\n"),
             Catch::Contains("shapes.count: given twice"));
  CHECK_THAT(error_of("preset: random2d\nname: \"x\nseed: 1\nshapes: {count: 2}\n"),
             Catch::Contains("name: the quoted string at line 2, column 7 is not closed on its line"));
  CHECK_THAT(error_of("preset: random2d\nname: x\nseed: 1\nshapes: 5\n"),
             Catch::Contains("shapes: must be a mapping of keys to values"));
  CHECK_THAT(error_of("preset: random2d\nname: x\nseed: 1e30\nshapes: {count: 2}\n"),
             Catch::Contains("seed: must be an integer of magnitude at most 2^53"));
  CHECK_THAT(error_of("preset: random2d\nname: '..'\nseed: 1\nshapes: {count: 2}\n"),
             Catch::Contains("name: must be 1-100 letters"));
  // a quote that is closed, with an escaped quote inside, is fine
  CHECK(error_of("preset: random2d\nname: 'it''s'\nseed: 1\nshapes: {count: 2}\n").find("quoted") ==
        std::string::npos);
}

}  // namespace test_dataset_identity
