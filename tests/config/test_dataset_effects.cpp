// `effects:` in a dataset config: the presets' shorthands are the paper's scene, a config's
// own effects replace them (lists, draws, scale), and the scene written to the shards parses
// back to the same scene.
#include <catch2/catch.hpp>

#include <string>

#include "hypershape/config/dataset.hpp"
#include "hypershape/config/scene.hpp"
#include "hypershape/core/input_error.hpp"

using namespace hypershape;

namespace {

double number(const physics::EffectSpec& e, const std::string& key) { return std::get<double>(e.params.at(key)); }

const char* multi = R"(preset: random2d
shapes: {count: 2}
effects:
  neo_hookean: {E: {uniform: [400, 600], sample: shape}, nu: 0.49}
  dirichlet_patch: {radius: {uniform: [0.3, 0.5]}}
  gaussian_traction:
    - {gamma: 0.2}
    - {gamma: {choice: [0.1, 0.3], sample: load}}
  body_force: {value: [0, -1], scale: fixed}
)";

}  // namespace

TEST_CASE("every preset's scene is the paper's: neo_hookean, dirichlet_patch, gaussian_traction",
          "[config][effects]") {
  for (const auto& p : config::presets()) {
    INFO(p.name);
    const auto c = config::parse_dataset_text(std::string("preset: ") + p.name + "\n", "<test>");
    CHECK_FALSE(c.scene_given);
    REQUIRE(c.scene.effects.size() == 3);
    CHECK(c.scene.effects[0].name == "neo_hookean");
    CHECK(number(c.scene.effects[0], "E") == c.material.E);
    CHECK(number(c.scene.effects[0], "nu") == c.material.nu);
    CHECK(number(c.scene.effects[1], "radius") == c.shapes.dirichlet_radius);
    CHECK(number(c.scene.effects[2], "gamma") == c.loads.gamma);
  }
}

TEST_CASE("a config's effects replace the preset's shorthands: lists, draws, scale",
          "[config][effects]") {
  const auto c = config::parse_dataset_text(multi, "<test>");
  REQUIRE(c.scene_given);
  const auto& e = c.scene.effects;
  REQUIRE(e.size() == 5);
  CHECK(e[2].label == "gaussian_traction.0");
  CHECK(e[3].path == "effects.gaussian_traction[1]");
  const auto& g = std::get<physics::Draw>(e[3].params.at("gamma"));
  CHECK(g.per == physics::Draw::Per::load);
  CHECK(g.kind == physics::Draw::Kind::choice);
  CHECK_FALSE(e[4].scaled);
  CHECK(c.shapes.dirichlet_radius == 0.5);  // the largest radius a shape may draw
  // The scene stored in the shards parses back to the same scene.
  const std::string yaml = config::effects_yaml(c.scene);
  std::string indented;
  for (std::size_t a = 0, b; a < yaml.size(); a = b + 1) {
    b = yaml.find('\n', a);
    if (b == std::string::npos) b = yaml.size();
    indented += "  " + yaml.substr(a, b - a) + "\n";
  }
  const auto back = config::parse_dataset_text("preset: random2d\nshapes: {count: 2}\neffects:\n" + indented, "<test>");
  CHECK(config::effects_yaml(back.scene) == yaml);
}

TEST_CASE("shorthands and effects do not mix in one config", "[config][effects]") {
  auto key_of = [](const std::string& text) {
    try {
      (void)config::parse_dataset_text(text, "<test>");
    } catch (const core::InputError& e) {
      return e.key();
    }
    return std::string("no error");
  };
  CHECK(key_of(std::string(multi) + "material: {E: 10}\n") == "material");
  CHECK(key_of(std::string(multi) + "loads: {gamma: 0.1}\n") == "loads.gamma");
  CHECK(key_of(std::string(multi) + "shapes: {count: 2, dirichlet_radius: 0.3}\n").rfind("shapes", 0) == 0);
}

TEST_CASE("a count of copies: copies 0..max-1, written back once with the count", "[config][effects]") {
  const std::string effects =
      "effects:\n  neo_hookean: {E: 500, nu: 0.49}\n  dirichlet_patch: {radius: 0.5}\n"
      "  gaussian_traction: {gamma: 0.2, count: {choice: [1, 3], sample: load}}\n";
  const auto c = config::parse_dataset_text("preset: random2d\n" + effects, "<test>");
  const auto tractions = c.scene.find("gaussian_traction");
  REQUIRE(tractions.size() == 3);
  CHECK(c.scene.effects[tractions[2]].label == "gaussian_traction.2");
  CHECK(c.scene.effects[tractions[2]].copy == 2);
  CHECK(config::effects_yaml(c.scene).find("count: {choice: [1, 3], sample: load}") != std::string::npos);
}
