#include "hypershape/config/dataset.hpp"

#include <cmath>
#include <limits>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <fmt/format.h>

#include "hypershape/mesh/surface_file.hpp"
#include "hypershape/physics/region.hpp"
#include "effects_block.hpp"
#include "solver_block.hpp"
#include "yaml_block.hpp"

namespace hypershape::config {

namespace {

/// shapes.base_file / shapes.base_dir (relative to the config file's directory) and, for a
/// directory family, the count from its files.
void parse_base_files(const YamlBlock& b, const std::string& base_dir, factory::ShapeConfig& s, std::int64_t& count,
                      bool has_count) {
  // Relative paths are relative to the config file's directory.
  auto path_key = [&](const char* key) {
    std::filesystem::path p = b.text(key);
    if (p.is_relative()) p = std::filesystem::path(base_dir) / p;
    return p.lexically_normal().string();
  };
  if (s.base == "file") {
    s.base_file = path_key("base_file");
    if (!std::filesystem::exists(s.base_file))
      b.fail("base_file", "no such file: " + s.base_file);
  } else if (b.has("base_file")) {
    b.fail("base_file", "only allowed with base: file");
  }
  if (s.base == "directory") {
    s.base_dir = path_key("base_dir");
    try {
      s.base_files = mesh::surface_files_in(s.base_dir);
    } catch (const InputError& e) {
      b.fail("base_dir", e.what());
    }
    if (s.base_files.empty())
      b.fail("base_dir", "no surface files (.stl, .msh) in " + s.base_dir);
    const auto n_files = std::int64_t(s.base_files.size());
    if (!has_count) count = n_files;
    if (count > n_files)
      b.fail("count", std::to_string(count) + " shapes, but " + s.base_dir + " holds " +
                          std::to_string(n_files) + " surface files (one shape per file)");
    s.base_files.resize(std::size_t(count));  // the first `count` files, by name
  } else if (b.has("base_dir")) {
    b.fail("base_dir", "only allowed with base: directory");
  }
  if (!has_count && s.base != "directory") b.fail("count", "missing (a number is required)");
}

/// shapes.steps: the [sigma, m] pairs of the deformation.
void parse_steps(const YamlBlock& b, factory::ShapeConfig& s) {
  // A directory family is the files as they are unless steps are given; the other families
  // are made by the steps.
  const YAML::Node steps = b.get("steps");
  if (s.base == "directory" ? (steps && !steps.IsSequence())
                            : (!steps || !steps.IsSequence() || steps.size() == 0))
    b.fail("steps", s.base == "directory"
                        ? "must be a list of [sigma, m] pairs (none: each file as it is)"
                        : "must be a non-empty list of [sigma, m] pairs");
  const std::size_t n_steps = steps && steps.IsSequence() ? steps.size() : 0;
  for (std::size_t k = 0; k < n_steps; ++k) {
    const auto& e = steps[k];
    const std::string key = "steps[" + std::to_string(k) + "]";
    if (!e.IsSequence() || e.size() != 2) b.fail(key, "must be a pair [sigma, m]");
    double sigma, m;
    try {
      sigma = e[0].as<double>();
      m = e[1].as<double>();
    } catch (const YAML::Exception&) {
      b.fail(key, "must be a pair of numbers [sigma, m]");
    }
    if (!(sigma >= 0.01 && sigma <= 2.0)) b.fail(key, "sigma must be in [0.01, 2]");
    if (!(m >= 0.0 && m <= 20.0)) b.fail(key, "m must be in [0, 20]");
    s.deformation.steps.push_back({sigma, m});
  }
}

/// shapes.quality: the mesh quality gate over its defaults.
void parse_quality(const YamlBlock& b, factory::ShapeConfig& s) {
  if (!b.has("quality")) return;
  YamlBlock q(b.get("quality"), b.file(), join(b.path(), "quality"));
  s.quality = mesh::QualityGate::defaults(s.dim);
  if (q.has("min_angle_deg")) {
    s.quality.min_angle_deg = q.number("min_angle_deg");
    if (!(s.quality.min_angle_deg >= 0 && s.quality.min_angle_deg < 60))
      q.fail("min_angle_deg", "must be in [0, 60)");
  }
  if (q.has("min_shape")) {
    s.quality.min_shape = q.number("min_shape");
    if (!(s.quality.min_shape >= 0 && s.quality.min_shape < 1)) q.fail("min_shape", "must be in [0, 1)");
  }
  q.allowed("min_angle_deg, min_shape");
  q.check_all_used();
}

void parse_shapes(const YamlBlock& b, const std::string& base_dir, factory::ShapeConfig& s,
                  std::int64_t& count, bool scene_given) {
  // count is read first (it is the first error to report) but a directory family may leave it
  // out: then it is the number of files.
  const bool has_count = b.has("count");
  // The plan, splits and manifest hold every shape id in memory: 10^8 is far past any dataset
  // that fits a disk (the size estimate refuses much less, see factory/preflight.hpp).
  if (has_count) count = b.integer("count", 1, 100000000, "shapes");
  const long dim = b.integer("dim");
  if (dim != 2 && dim != 3) b.fail("dim", "must be 2 or 3");
  s.dim = int(dim);
  s.base = b.text("base");
  if (s.base != "circle" && s.base != "sphere" && s.base != "file" && s.base != "directory")
    b.fail("base", "must be circle (2D), sphere (3D), file (3D surface) or directory (3D: one shape "
                   "per surface file), got '" + s.base + "'");
  if ((s.base == "circle") != (s.dim == 2))
    b.fail("base", s.base + " needs dim " + (s.base == "circle" ? "2" : "3") +
                       " (circle: 2D; sphere, file, directory: 3D)");
  parse_base_files(b, base_dir, s, count, has_count);
  parse_steps(b, s);
  auto optional_number = [&](const char* key, double& out, double lo, double hi) {
    if (!b.has(key)) return;
    out = b.number(key);
    if (!(out >= lo && out <= hi))
      b.fail(key, "must be in [" + fmt_number(lo) + ", " + fmt_number(hi) + "]");
  };
  optional_number("velocity_unit", s.deformation.velocity_unit, 0.0, 1.0);
  optional_number("nodes_per_sigma", s.deformation.nodes_per_sigma, 2.0, 16.0);
  s.h = b.number("h");
  if (!(s.h >= 0.005 && s.h <= 0.5)) b.fail("h", "must be in [0.005, 0.5]");
  if (scene_given && b.has("dirichlet_radius"))
    b.fail("dirichlet_radius", "a shorthand of effects.dirichlet_patch.radius: with effects: set it there");
  if (!scene_given) s.dirichlet_radius = b.number("dirichlet_radius");
  if (!(s.dirichlet_radius >= 0.0 && s.dirichlet_radius <= 2.0))
    b.fail("dirichlet_radius", "must be in [0, 2] (0: no Dirichlet patch)");
  optional_number("max_turn_deg", s.max_turn_deg, 2.0, 45.0);
  optional_number("min_feature_fraction", s.min_feature_fraction, 0.0, 1.0);
  if (b.has("max_attempts")) {
    const long a = b.integer("max_attempts");
    if (a < 1 || a > 1000) b.fail("max_attempts", "must be in [1, 1000]");
    s.max_attempts = int(a);
  }
  parse_quality(b, s);
  b.allowed("count, dim, base, base_file, base_dir, steps, velocity_unit, nodes_per_sigma, h, dirichlet_radius, "
            "max_turn_deg, min_feature_fraction, max_attempts, quality");
  b.check_all_used();
}

/// The sections that are mappings, checked before the preset is merged in (a scalar there
/// would otherwise replace the preset's mapping, or reach yaml-cpp's operator[]).
void check_sections(const YAML::Node& root, const std::string& source) {
  const YamlBlock top(root, source, "");
  for (const char* s : {"shapes", "loads", "material", "effects", "mesh", "representations", "accuracy", "split",
                        "output", "solver", "petsc"})
    (void)top.mapping(s);
}

/// The dataset's name is a directory name (results/<name> without -o) and a file-name part.
void check_name(const YamlBlock& top, const std::string& name) {
  const bool word = !name.empty() && name.size() <= 100 && name.find_first_not_of(
      "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_.-") == std::string::npos;
  if (!word || name.front() == '.' || name.front() == '-')
    top.fail("name", "must be 1-100 letters, digits, '_', '-' or '.', not starting with '.' or '-' (it names "
                     "the output directory results/<name>), got '" + name + "'");
}

/// Merges `over` into `base`: mappings key by key (recursively), anything else replaced.
YAML::Node merge(const YAML::Node& base, const YAML::Node& over) {
  if (!base || !base.IsMap() || !over || !over.IsMap()) return YAML::Clone(over);
  YAML::Node out = YAML::Clone(base);
  for (const auto& kv : over) {
    const std::string k = kv.first.Scalar();
    out[k] = merge(out[k], kv.second);
  }
  return out;
}

void parse_loads(const YamlBlock& b, LoadsConfig& l) {
  if (b.has("count")) {
    const long n = b.integer("count");
    if (n < 1 || n > 1000000) b.fail("count", "must be in [1, 1000000] (load cases per shape)");
    l.count = int(n);
  }
  if (b.has("gamma")) l.gamma = b.number("gamma");
  if (!(l.gamma >= 0.005 && l.gamma <= 2.0)) b.fail("gamma", "must be in [0.005, 2]");
  if (b.has("target")) {
    const auto t = b.vector("target", 2);
    l.target_min = t[0];
    l.target_max = t[1];
  }
  if (!(l.target_min > 0 && l.target_min <= l.target_max && l.target_max <= 2.0))
    b.fail("target", "must be [min, max] with 0 < min <= max <= 2 (max|u| in the box [-1, 1]^d)");
  b.allowed("count, gamma, target");
  b.check_all_used();
}

void parse_material(const YamlBlock& b, MaterialConfig& m) {
  if (b.has("E")) m.E = b.number("E");
  if (!(m.E > 0)) b.fail("E", "must be > 0");
  if (b.has("nu")) m.nu = b.number("nu");
  if (!(m.nu > -1 && m.nu < 0.5)) b.fail("nu", "must be in (-1, 0.5)");
  if (b.has("dilatation")) m.dilatation = b.text("dilatation");
  if (m.dilatation != "pointwise" && m.dilatation != "mean")
    b.fail("dilatation", "'" + m.dilatation + "' is not one of: pointwise, mean");
  b.allowed("E, nu, dilatation");
  b.check_all_used();
}

bool flag(const YamlBlock& b, const std::string& key, bool fallback) {
  return b.has(key) ? b.boolean(key) : fallback;
}

/// The scene the shorthands stand for: the paper's three effects.
physics::SceneSpec shorthand_scene(const DatasetConfig& c, const std::string& source) {
  physics::SceneSpec s;
  s.source = source;
  auto add = [&](const char* name, std::map<std::string, physics::ParamValue> params) {
    s.effects.push_back({name, name, std::string("effects.") + name, std::move(params), true, false, {}, 0});
  };
  std::map<std::string, physics::ParamValue> material{{"E", c.material.E}, {"nu", c.material.nu}};
  if (c.material.dilatation != "pointwise") material["dilatation"] = c.material.dilatation;  // else: as before
  add("neo_hookean", std::move(material));
  if (c.shapes.dirichlet_radius > 0) add("dirichlet_patch", {{"radius", c.shapes.dirichlet_radius}});
  add("gaussian_traction", {{"gamma", c.loads.gamma}});
  return s;
}

/// Placeholders for what the factory draws on each shape (for validation).
void placeholders(const physics::SceneSpec& spec, int dim, std::size_t i, physics::EffectParams& p) {
  const auto& e = spec.effects[i];
  std::vector<double> e1(std::size_t(dim), 0.0);
  e1[0] = 1.0;
  if (e.name == "dirichlet_patch") p.set("center", std::vector<double>(std::size_t(dim), 0.0));
  if (e.name == "gaussian_traction") {
    if (!e.params.count("center")) p.set("center", e1);
    if (!e.params.count("direction")) p.set("direction", e1);
  }
}

/// Effect `i` of the dataset scene at the low end of its draws, placeholders filled in.
physics::EffectPtr make_one(const DatasetConfig& c, std::size_t i) {
  const auto resolved = physics::resolve(
      c.scene, [](std::size_t, const std::string&, const physics::Draw& d) { return d.low(); },
      [&](std::size_t k, physics::EffectParams& p) { placeholders(c.scene, c.shapes.dim, k, p); });
  return physics::build_effect(resolved[i], c.shapes.dim);
}

/// A dataset's `dirichlet` effects: fixed regions (no draws), every component fixed (the stored
/// dirichlet_mask means u = 0); each becomes a facet selector of the shape family, so that its
/// facets join the shape's Dirichlet facets (mask, distance, load placements).
void check_fixed_supports(DatasetConfig& c) {
  const auto& spec = c.scene;
  c.shapes.fixed_supports.clear();
  for (auto i : spec.find("dirichlet")) {
    const auto& e = spec.effects[i];
    if (e.params.count("components"))
      throw InputError(c.source, e.path + ".components",
                       "a dataset's Dirichlet regions fix every component (the stored dirichlet_mask means u = 0); "
                       "sliding supports are for scenes");
    for (const auto& [key, value] : e.params)
      if (std::holds_alternative<physics::Draw>(value))
        throw InputError(c.source, e.path + "." + key, "a fixed region: give numbers (a drawn support is the "
                                                       "dirichlet_patch)");
    physics::EffectParams p(c.source, e.path);
    for (const auto& [key, value] : e.params) {
      if (const auto* d = std::get_if<double>(&value)) p.set(key, *d);
      else if (const auto* v = std::get_if<std::vector<double>>(&value)) p.set(key, *v);
      else p.set(key, std::get<std::string>(value));
    }
    c.shapes.fixed_supports.push_back(physics::Region::from_params(p, c.shapes.dim, true).facets());
  }
}

/// Rejects, before any work, a dataset scene the factory cannot run: unknown effects or keys,
/// values out of range at either end of a distribution, draws per load case of what is set up
/// once per shape, no or two materials, two dirichlet_patch or no Dirichlet support, a drawn or
/// sliding dirichlet region, no load scaled by alpha.
void check_dataset_scene(DatasetConfig& c) {
  const auto& spec = c.scene;
  const int dim = c.shapes.dim;
  const auto patches = spec.find("dirichlet_patch");
  if (patches.size() > 1)
    throw InputError(c.source, spec.effects[patches[1]].path,
                     "a dataset has at most one dirichlet_patch (its centre is drawn on each shape's boundary "
                     "and the mesh conforms to its ends); add fixed regions as dirichlet: [{box: [lower corner, "
                     "upper corner]}, {center: [...], radius: r}, ...]");
  check_fixed_supports(c);
  if (patches.empty() && spec.find("dirichlet").empty())
    throw InputError(c.source, "effects", "a dataset needs a Dirichlet support: a dirichlet_patch (drawn on each "
                                          "shape) and/or dirichlet regions (fixed: box or center + radius)");
  if (patches.empty()) {
    c.shapes.dirichlet_radius = 0.0;  // no drawn patch: only the fixed regions
  } else if (spec.effects[patches[0]].params.count("center")) {
    throw InputError(c.source, spec.effects[patches[0]].path + ".center",
                     "drawn on each shape's boundary by the factory: leave it out");
  }
  std::vector<physics::EffectPtr> built;
  for (int corner = 0; corner < 2; ++corner) {
    if (corner == 0)  // before the checks of the whole: copies of a material are two materials
      for (std::size_t i = 0; i < spec.effects.size(); ++i)
        if (spec.effects[i].count && spec.effects[i].copy == 0 && !make_one(c, i)->has_load())
          throw InputError(c.source, spec.effects[i].path + ".count", "only a load (a traction, a body force) has copies");
    const auto resolved = physics::resolve(
        spec, [&](std::size_t, const std::string&, const physics::Draw& d) { return corner ? d.high() : d.low(); },
        [&](std::size_t i, physics::EffectParams& p) { placeholders(spec, dim, i, p); });
    built = physics::build_effects(c.source, resolved, dim, true);
  }
  for (std::size_t i = 0; i < spec.effects.size(); ++i) {
    const auto& e = spec.effects[i];
    for (const auto& [key, value] : e.params) {
      const auto* d = std::get_if<physics::Draw>(&value);
      if (!d) continue;
      if (d->per == physics::Draw::Per::load && !built[i]->has_load())
        throw InputError(c.source, e.path + "." + key,
                         "drawn per load case, but " + e.name + " is set up once per shape (sample: shape)");
      if (e.name == "gaussian_traction" && (key == "center" || key == "direction"))
        throw InputError(c.source, e.path + "." + key, "a vector: give it fixed, or leave it out to draw it");
    }
  }
  if (!patches.empty()) {
    const auto& patch = spec.effects[patches[0]];
    const auto r = patch.params.find("radius");
    if (r != patch.params.end()) {
      if (const auto* d = std::get_if<physics::Draw>(&r->second)) c.shapes.dirichlet_radius = d->high();
      else if (const auto* v = std::get_if<double>(&r->second)) c.shapes.dirichlet_radius = *v;
    }
    if (!(c.shapes.dirichlet_radius > 0 && c.shapes.dirichlet_radius <= 2.0))
      throw InputError(c.source, patch.path + ".radius", "must be in (0, 2]");
  }
  for (auto i : spec.find("neo_hookean"))
    for (auto [key, out] : {std::pair{"E", &c.material.E}, std::pair{"nu", &c.material.nu}})
      if (auto it = spec.effects[i].params.find(key); it != spec.effects[i].params.end())
        if (const auto* v = std::get_if<double>(&it->second)) *out = *v;
}

/// `effects:` replaces the preset's shorthands; the config's own may not be mixed with it.
void drop_shorthands(YAML::Node& preset, const YAML::Node& own, const std::string& source) {
  if (own["material"]) throw InputError(source, "material", "a shorthand of effects.neo_hookean: with effects: set it there");
  if (own["loads"] && own["loads"]["gamma"])
    throw InputError(source, "loads.gamma", "a shorthand of effects.gaussian_traction.gamma: with effects: set it there");
  preset.remove("material");
  if (preset["loads"]) preset["loads"].remove("gamma");
  if (preset["shapes"]) preset["shapes"].remove("dirichlet_radius");
}

/// A config naming a preset: the preset's YAML merged under the config's (which wins); relative
/// paths stay relative to the preset's directory unless the config gives its own.
YAML::Node merge_preset(YAML::Node root, const std::string& source, DatasetConfig& c, std::string& base_dir) {
  YamlBlock top(root, source, "");
  c.preset = top.text("preset");
  const Preset* found = nullptr;
  std::string names;
  for (const auto& p : presets()) {
    names += (names.empty() ? "" : ", ") + std::string(p.name);
    if (c.preset == p.name) found = &p;
  }
  if (!found) top.fail("preset", "unknown preset '" + c.preset + "'; presets: " + names);
  YAML::Node base = YAML::Load(found->text);
  root.remove("preset");
  if (root["effects"]) drop_shorthands(base, root, source);
  // A preset's relative paths (base_file, base_dir) stay relative to the preset's directory
  // unless the config gives its own.
  if (!(root["shapes"] && (root["shapes"]["base_file"] || root["shapes"]["base_dir"])))
    base_dir = found->directory;
  root = merge(base, root);
  return root;
}

/// mesh: degree, and in 3D the mesh, surface and rim edge lengths.
void parse_mesh(const YamlBlock& top, const std::string& source, DatasetConfig& c) {
  YamlBlock m(top.get("mesh"), source, "mesh");
  if (m.has("degree")) {
    const long d = m.integer("degree");
    if (d != 1 && d != 2) m.fail("degree", "must be 1 or 2");
    c.degree = int(d);
  }
  if (m.has("quadrature")) {
    const long q = m.integer("quadrature");
    const int lowest = c.degree == 1 ? 1 : 2;
    if (q < lowest || q > 8)
      m.fail("quadrature", fmt::format("must be an integer in [{}, 8]: the polynomial degree the cell rule "
                                       "integrates exactly (default 2 x degree - 1; below 2, P2 has "
                                       "zero-energy modes)", lowest));
    c.quadrature = int(q);
  }
  if (m.has("h")) {
    const double mh = m.number("h");
    if (c.shapes.dim != 3)
      m.fail("h", "only for 3D shapes (a 2D boundary is resolved by curvature and shapes.h; "
                  "set shapes.h)");
    if (!(mh >= c.shapes.h && mh <= 0.5))
      m.fail("h", fmt::format("must be in [shapes.h = {:g}, 0.5] (the mesh is never finer than "
                              "the surface the shape is drawn at; the 3D presets set mesh.h "
                              "(0.2 or 0.3): with a coarser shapes.h set mesh.h too)", c.shapes.h));
    c.shapes.mesh_h = mh;
  }
  if (m.has("surface_h")) {
    const double sh = m.number("surface_h");
    if (c.shapes.dim != 3) m.fail("surface_h", "only for 3D shapes");
    const double mh = std::max(c.shapes.h, c.shapes.mesh_h);
    if (!(sh >= c.shapes.h && sh <= mh))
      m.fail("surface_h", fmt::format("must be in [shapes.h = {:g}, mesh.h = {:g}] (shapes.h: the surface "
                                      "as drawn, with a coarser interior; a preset's surface_h (random3d: "
                                      "0.22) stays under a finer mesh.h you set: set surface_h too)",
                                      c.shapes.h, mh));
    c.shapes.surface_h = sh;
  }
  if (m.has("rim")) {
    const double rim = m.number("rim");
    // Without a Dirichlet region there is nothing to grade: the key is then without effect (a
    // preset's rim stays valid under a config that drops the patch).
    if (!(rim >= 0 && rim <= std::max(c.shapes.h, c.shapes.mesh_h)))
      m.fail("rim", fmt::format("must be in [0, {:g}] (edge length at the clamp rim, 2D: at the patch ends; "
                                "at most {}; 0: not graded)", std::max(c.shapes.h, c.shapes.mesh_h),
                                c.shapes.dim == 2 ? "shapes.h" : "mesh.h"));
    c.shapes.rim_size = rim;
  }
  m.allowed("degree, quadrature (exactness of the cell rule), h (3D: mesh edge length when coarser than "
            "shapes.h), surface_h (3D: surface edge length, shapes.h keeps it as drawn), rim (edge length at "
            "the clamp rim; 2D: at the patch ends)");
  m.check_all_used();
}

void parse_representations(const YamlBlock& top, const std::string& source, DatasetConfig& c) {
  YamlBlock r(top.get("representations"), source, "representations");
  auto& rep = c.representations;
  rep.point_cloud = flag(r, "point_cloud", true);
  rep.grid = flag(r, "grid", true);
  rep.grid_size = c.shapes.dim == 2 ? 128 : 64;
  if (r.has("grid_size")) {
    const long n = r.integer("grid_size");
    if (n < 2 || n > (c.shapes.dim == 2 ? 4096 : 512))
      r.fail("grid_size", c.shapes.dim == 2 ? "must be in [2, 4096]" : "must be in [2, 512]");
    rep.grid_size = int(n);
  }
  rep.error_estimate = flag(r, "error_estimate", false);
  r.allowed("point_cloud, grid, grid_size, error_estimate");
  r.check_all_used();
}

/// accuracy: the bound (required when the block is given) and the ladder's limits; it implies
/// the error estimate (the indicator), so `representations.error_estimate: false` contradicts it.
void parse_accuracy(const YamlBlock& top, const std::string& source, DatasetConfig& c) {
  if (!top.has("accuracy")) return;
  YamlBlock a(top.get("accuracy"), source, "accuracy");
  auto& acc = c.accuracy;
  if (!a.has("rel_l2")) a.fail("rel_l2", "missing (the bound on each load case's estimated relative L2 error of u, "
                                         "a number in (0, 1), e.g. 0.01)");
  acc.rel_l2 = a.number("rel_l2");
  if (!(acc.rel_l2 > 0 && acc.rel_l2 < 1)) a.fail("rel_l2", "must be a number in (0, 1), e.g. 0.01");
  if (a.has("max_level")) {
    const long l = a.integer("max_level");
    if (l < 0 || l > 3) a.fail("max_level", "must be in [0, 3] (the finest level of the ladder)");
    acc.max_level = int(l);
  }
  if (a.has("exceed_share")) {
    acc.exceed_share = a.number("exceed_share");
    if (!(acc.exceed_share >= 0 && acc.exceed_share <= 0.5))
      a.fail("exceed_share", "must be in [0, 0.5] (share of a shape's load cases allowed above the bound)");
  }
  if (a.has("start")) {
    const std::string start = a.text("start");
    if (start != "coarse" && start != "rest")
      a.fail("start", "must be rest (every re-solve from rest, the default) or coarse (one level at a time, each "
                      "re-solve from the state the level below's estimate reached)");
    acc.start_from_coarse = start == "coarse";
  }
  if (a.has("resolve_newton_budget")) {
    const long b = a.integer("resolve_newton_budget");
    if (b < 1 || b > 100000)
      a.fail("resolve_newton_budget", "must be an integer in [1, 100000] (Newton iterations a re-solve above level 0 may "
                                      "spend; default: solver.newton_budget)");
    acc.resolve_newton_budget = int(b);
  }
  acc.resolve_retries = flag(a, "resolve_retries", true);
  a.allowed("rel_l2, max_level, exceed_share, start, resolve_newton_budget, resolve_retries");
  a.check_all_used();
  const YAML::Node rep = top.get("representations");
  if (rep && rep["error_estimate"] && !c.representations.error_estimate)
    throw InputError(source, "representations.error_estimate",
                     "accuracy: needs the error estimate (it is the indicator): leave error_estimate out or true");
  c.representations.error_estimate = true;
  if (acc.max_level > 0 && c.quadrature == 1)
    throw InputError(source, "mesh.quadrature", "1 with accuracy: the ladder goes on to P2, which needs at least 2");
}

void parse_split(const YamlBlock& top, const std::string& source, DatasetConfig& c) {
  YamlBlock s(top.get("split"), source, "split");
  auto& sp = c.split;
  if (s.has("train")) sp.train = s.number("train");
  if (s.has("val")) sp.val = s.number("val");
  if (s.has("test")) sp.test = s.number("test");
  if (sp.train < 0 || sp.val < 0 || sp.test < 0 || std::abs(sp.train + sp.val + sp.test - 1.0) > 1e-9)
    s.fail("", "train, val and test must be >= 0 and sum to 1");
  s.allowed("train, val, test");
  s.check_all_used();
}

void parse_output(const YamlBlock& top, const std::string& source, DatasetConfig& c) {
  YamlBlock o(top.get("output"), source, "output");
  if (o.has("shard_size")) {
    const long n = o.integer("shard_size");
    if (n < 1 || n > 100000) o.fail("shard_size", "must be in [1, 100000] (shapes per shard)");
    c.shard_size = int(n);
  }
  o.allowed("shard_size");
  o.check_all_used();
}

/// The resolved config, stored with the data: the preset merged in, paths made absolute, the
/// count of a directory family written out, and its files listed (in comments: the text is
/// the dataset's identity, so a rerun on other files is another dataset).
std::string resolved_text(YAML::Node root, const DatasetConfig& c) {
  if (!c.shapes.base_file.empty()) root["shapes"]["base_file"] = c.shapes.base_file;
  std::string files;
  if (c.shapes.base == "directory") {
    root["shapes"]["base_dir"] = c.shapes.base_dir;
    root["shapes"]["count"] = c.n_shapes;
    files = "# shapes.base_dir: shape i is file i of\n";
    for (std::size_t i = 0; i < c.shapes.base_files.size(); ++i)
      files += "#   " + std::to_string(i) + ": " +
               std::filesystem::path(c.shapes.base_files[i]).filename().string() + "\n";
  }
  YAML::Emitter e;
  e << root;
  return std::string("# hypershape dataset config, resolved") +
           (c.preset.empty() ? "" : " from preset " + c.preset) + "\n" + e.c_str() + "\n" + files;
}

}  // namespace


const char* default_dataset_text() {
  return R"(# The embedded default dataset: a small slice of Random2D (seed paper, Table 1).
preset: random2d
name: default
shapes: {count: 4}
loads: {count: 6}
representations: {grid_size: 64}
output: {shard_size: 2}
)";
}

DatasetConfig parse_dataset_text(const std::string& text, const std::string& source,
                                 const std::string& base_dir_in) {
  YAML::Node root = load_yaml(text, source);
  if (!root || !root.IsMap()) throw InputError(source, "", "a dataset config must be a YAML mapping");
  check_sections(root, source);
  DatasetConfig c;
  c.source = source;
  std::string base_dir = base_dir_in;
  if (root["preset"]) root = merge_preset(root, source, c, base_dir);
  YamlBlock top(root, source, "");
  c.name = top.text("name");
  check_name(top, c.name);
  c.seed = std::uint64_t(top.integer("seed", 0, std::numeric_limits<long>::max()));
  if (!top.has("shapes")) top.fail("shapes", "missing (the shape family is required)");
  c.scene_given = bool(root["effects"]);
  if (c.scene_given && root["material"])
    top.fail("material", "a shorthand of effects.neo_hookean: with effects: set it there");
  if (c.scene_given && root["loads"] && root["loads"]["gamma"])
    throw InputError(source, "loads.gamma", "a shorthand of effects.gaussian_traction.gamma: with effects: set it there");
  parse_shapes(YamlBlock(top.get("shapes"), source, "shapes"), base_dir, c.shapes, c.n_shapes, c.scene_given);
  c.shapes.name = c.name;
  // The paper's widths: gamma 0.2 in 2D, 0.1 in 3D.
  c.loads.gamma = c.shapes.dim == 2 ? 0.2 : 0.1;
  parse_loads(YamlBlock(top.get("loads"), source, "loads"), c.loads);
  parse_material(YamlBlock(top.get("material"), source, "material"), c.material);
  if (c.scene_given) {
    c.scene = parse_effects(YamlBlock(top.get("effects"), source, "effects"), true);
    check_dataset_scene(c);
  } else {
    c.scene = shorthand_scene(c, source);
  }
  parse_mesh(top, source, c);
  parse_representations(top, source, c);
  parse_accuracy(top, source, c);
  parse_split(top, source, c);
  parse_output(top, source, c);
  parse_solver_block(YamlBlock(top.get("solver"), source, "solver"), c.solver);
  parse_petsc_block(YamlBlock(top.get("petsc"), source, "petsc"), c.petsc);
  top.allowed("preset, name, seed, shapes, loads, material, effects, mesh, representations, accuracy, split, output, "
              "solver, petsc");
  top.check_all_used();
  c.text = resolved_text(root, c);
  return c;
}

DatasetConfig mini_dataset(const DatasetConfig& full) {
  YAML::Node root = YAML::Load(full.text);
  const bool one_shape = full.n_shapes == 1;
  root["name"] = full.name + "_mini";
  root["shapes"]["count"] = std::min<std::int64_t>(full.n_shapes, full.shapes.dim == 3 ? 2 : 4);
  root["loads"]["count"] = std::min<long>(full.loads.count, one_shape ? 4 : 2);
  root["representations"]["grid_size"] = full.shapes.dim == 3 ? 16 : 32;
  root["output"]["shard_size"] = 2;
  YAML::Emitter e;
  e << root;
  return parse_dataset_text(e.c_str(), full.source + " (--mini)");
}

DatasetConfig preset_dataset(const std::string& name) {
  return parse_dataset_text("preset: " + name + "\n", "--preset " + name);
}

DatasetConfig parse_dataset_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, "", "cannot open the dataset config");
  std::stringstream ss;
  ss << in.rdbuf();
  const auto dir = std::filesystem::path(path).parent_path().string();
  return parse_dataset_text(ss.str(), path, dir.empty() ? "." : dir);
}

}  // namespace hypershape::config
