#include "hypershape/config/scene.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "hypershape/core/error.hpp"
#include "effects_block.hpp"
#include "solver_block.hpp"
#include "yaml_block.hpp"

namespace hypershape::config {

using core::InputError;


const char* default_scene_text() {
  return R"(# The default scene: the seed paper's set-up (section 3.2, appendix A) on the unit disk.
geometry: {base: circle}
mesh: {h: 0.05, degree: 1, clamp_refinement: 0.25}
effects:
  neo_hookean: {E: 500, nu: 0.49}
  dirichlet_patch: {center: [1.0, 0.0], radius: 0.5}
  gaussian_traction: {center: [-1.0, 0.0], direction: [0.0, 1.0], gamma: 0.2}
load: {target: 0.3}
)";
}

Scene parse_scene_text(const std::string& text, const std::string& source, const std::string& base_dir) {
  YAML::Node root = load_yaml(text, source);
  if (!root || !root.IsMap()) throw InputError(source, "", "a scene must be a YAML mapping");
  Scene s;
  s.source = source;
  s.text = text;
  YamlBlock top(root, source, "");
  top.allowed("geometry, mesh, effects, load, solver, petsc");
  for (const auto& kv : root) {
    static const std::set<std::string> sections = {"geometry", "mesh", "effects", "load", "solver", "petsc"};
    if (!sections.count(kv.first.Scalar()))
      top.fail(kv.first.Scalar(), "unknown key; allowed: geometry, mesh, effects, load, solver, petsc");
  }

  YamlBlock geo(top.get("geometry"), source, "geometry");
  if (!top.has("geometry")) top.fail("geometry", "missing (e.g. geometry: {base: circle})");
  s.base = geo.text("base");
  if (s.base == "circle") {
    s.dim = 2;
  } else if (s.base == "sphere") {
    s.dim = 3;
  } else if (s.base == "file") {
    namespace fs = std::filesystem;
    fs::path p = geo.text("file");
    if (p.is_relative()) p = fs::path(base_dir) / p;
    std::error_code ec;
    if (!fs::is_regular_file(p, ec)) geo.fail("file", "no such mesh file: " + p.string());
    s.mesh_file = p.string();
    s.dim = 0;
  } else {
    geo.fail("base", "unknown base shape '" + s.base + "'; allowed: circle, sphere, file");
  }
  geo.allowed("base, file");
  geo.check_all_used();

  YamlBlock mesh(top.get("mesh"), source, "mesh");
  if (mesh.has("h")) {
    s.h = mesh.number("h");
    if (!(s.h > 0 && s.h <= 1)) mesh.fail("h", "must be in (0, 1]");
  }
  if (mesh.has("degree")) {
    s.degree = int(mesh.integer("degree"));
    if (s.degree != 1 && s.degree != 2) mesh.fail("degree", "must be 1 or 2");
  }
  if (mesh.has("clamp_refinement")) {
    s.clamp_refinement = mesh.number("clamp_refinement");
    if (!(s.clamp_refinement > 0 && s.clamp_refinement <= 1))
      mesh.fail("clamp_refinement", "must be in (0, 1] (element size at the patch ends / h)");
  }
  mesh.allowed("h, degree, clamp_refinement");
  mesh.check_all_used();

  if (!top.has("effects")) top.fail("effects", "missing (a mapping of effect names to parameters)");
  s.effects = parse_effects(YamlBlock(top.get("effects"), source, "effects"), false);

  YamlBlock load(top.get("load"), source, "load");
  if (!top.has("load")) top.fail("load", "missing (load: {target: 0.3} or load: {alpha: 10})");
  if (load.has("alpha") == load.has("target")) load.fail("", "give exactly one of alpha, target");
  if (load.has("alpha")) {
    s.alpha = load.number("alpha");
    if (!(*s.alpha >= 0)) load.fail("alpha", "must be >= 0");
  } else {
    s.target = load.number("target");
    if (!(*s.target > 0 && *s.target <= 2)) load.fail("target", "must be in (0, 2]");
  }
  load.allowed("alpha, target");
  load.check_all_used();

  parse_solver_block(YamlBlock(top.get("solver"), source, "solver"), s.solver);
  parse_petsc_block(YamlBlock(top.get("petsc"), source, "petsc"), s.petsc);
  top.check_all_used();
  return s;
}

Scene parse_scene_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, "", "cannot open the scene file");
  std::stringstream ss;
  ss << in.rdbuf();
  return parse_scene_text(ss.str(), path, std::filesystem::path(path).parent_path().string().empty()
                                              ? "."
                                              : std::filesystem::path(path).parent_path().string());
}

}  // namespace hypershape::config
