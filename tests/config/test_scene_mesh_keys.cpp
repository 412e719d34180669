// A scene expresses every discretisation choice a dataset makes (issue 16): each preset's
// `mesh:` block, copied unchanged into a scene, is accepted by the scene parser
// (`hypershape solve`) with the same degree and h.
#include <catch2/catch.hpp>

#include <string>

#include "hypershape/config/dataset.hpp"
#include "hypershape/config/scene.hpp"

using namespace hypershape;

namespace {

/// The preset's `mesh:` line (flow mapping), without its comment; empty if it has none.
std::string mesh_line(const std::string& text) {
  const auto at = text.find("\nmesh:");
  if (at == std::string::npos) return "";
  std::string line = text.substr(at + 1, text.find('\n', at + 1) - at - 1);
  return line.substr(0, line.find('#'));
}

}  // namespace

TEST_CASE("every preset's mesh block is a valid scene mesh block", "[config]") {
  int n_checked = 0;
  for (const auto& p : config::presets()) {
    const std::string mesh = mesh_line(p.text);
    if (mesh.empty()) continue;
    INFO("preset " << p.name << ": " << mesh);
    const auto cfg = config::parse_dataset_text(p.text, p.name, p.directory);
    const std::string scene_text = "geometry: {base: " + std::string(cfg.shapes.dim == 3 ? "sphere" : "circle") + "}\n" +
                                   mesh + "\neffects:\n  neo_hookean: {E: 500, nu: 0.49}\n"
                                   "  dirichlet_patch: {center: [1, 0" + (cfg.shapes.dim == 3 ? ", 0" : "") +
                                   "], radius: 0.4}\nload: {target: 0.3}\n";
    config::Scene s;
    REQUIRE_NOTHROW(s = config::parse_scene_text(scene_text, "<test>"));
    CHECK(s.degree == cfg.degree);
    if (cfg.shapes.mesh_h > 0) CHECK(s.h == cfg.shapes.mesh_h);
    CHECK(s.rim_size == cfg.shapes.rim_size);
    ++n_checked;
  }
  CHECK(n_checked >= 6);  // the four 3D presets and the two 2D ones with a mesh block
}
