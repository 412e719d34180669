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

namespace {

/// polygon: [[x, y], ...]: at least 3 points of 2 finite numbers each.
void parse_polygon(const YamlBlock& geo, Scene& s) {
  const YAML::Node n = geo.get("polygon");
  if (!n.IsSequence() || n.size() < 3) geo.fail("polygon", "must be a list of >= 3 points [x, y]");
  for (std::size_t i = 0; i < n.size(); ++i) {
    const std::string key = "polygon[" + std::to_string(i) + "]";
    if (!n[i].IsSequence() || n[i].size() != 2) geo.fail(key, "must be a point [x, y]");
    std::array<double, 2> p{};
    for (std::size_t k = 0; k < 2; ++k) {
      try {
        p[k] = n[i][k].as<double>();
      } catch (const YAML::Exception&) {
        geo.fail(key, "must be a point [x, y] of numbers");
      }
      if (!std::isfinite(p[k])) geo.fail(key, "must be a point [x, y] of finite numbers");
    }
    s.polygon.push_back(p);
  }
}

void parse_geometry(const YamlBlock& geo, const std::string& base_dir, Scene& s) {
  if (geo.has("polygon")) {
    if (geo.has("base")) geo.fail("base", "give either base or polygon");
    s.base = "polygon";
    s.dim = 2;
    parse_polygon(geo, s);
    geo.allowed("base, file, polygon");
    geo.check_all_used();
    return;
  }
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
    geo.fail("base", "unknown base shape '" + s.base + "'; allowed: circle, sphere, file (or polygon: [[x, y], ...])");
  }
  geo.allowed("base, file, polygon");
  geo.check_all_used();
}

}  // namespace

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

  if (!top.has("geometry")) top.fail("geometry", "missing (e.g. geometry: {base: circle})");
  parse_geometry(YamlBlock(top.get("geometry"), source, "geometry"), base_dir, s);

  YamlBlock mesh(top.get("mesh"), source, "mesh");
  if (mesh.has("h")) {
    s.h = mesh.number("h");
    if (s.base == "polygon" ? !(s.h > 0) : !(s.h > 0 && s.h <= 1))
      mesh.fail("h", s.base == "polygon" ? "must be > 0 (in the polygon's length unit)" : "must be in (0, 1]");
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
  for (const char* key : {"surface_h", "rim"}) {
    if (!mesh.has(key)) continue;
    const double v = mesh.number(key);
    const bool disk_rim = s.dim == 2 && s.base == "circle" && std::string(key) == "rim";
    if (!disk_rim && (s.dim != 3 || s.base != "sphere"))
      mesh.fail(key, std::string(key) == "rim" ? "only for geometry {base: sphere} or {base: circle} (the datasets' key)"
                                                : "only for geometry {base: sphere} (the datasets' 3D key)");
    if (!(v > 0 && v <= 1)) mesh.fail(key, "must be in (0, 1] (an edge length)");
    (std::string(key) == "rim" ? s.rim_size : s.surface_h) = v;
  }
  if (s.dim == 2 && mesh.has("rim") && mesh.has("clamp_refinement"))
    mesh.fail("rim", "give one of rim (the size at the patch ends) and clamp_refinement (that size / h)");
  mesh.allowed("h, degree, clamp_refinement, surface_h, rim");
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
