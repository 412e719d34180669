#include "hypershape/config/dataset.hpp"

#include <filesystem>
#include <fstream>
#include <sstream>

#include "yaml_block.hpp"

namespace hypershape::config {

namespace {

void parse_shapes(YamlBlock& b, const std::string& base_dir, factory::ShapeConfig& s,
                  std::int64_t& count) {
  const long n = b.integer("count");
  if (n < 1) b.fail("count", "must be >= 1");
  count = n;
  const long dim = b.integer("dim");
  if (dim != 2 && dim != 3) b.fail("dim", "must be 2 or 3");
  s.dim = int(dim);
  s.base = b.text("base");
  if (s.base != "circle" && s.base != "sphere" && s.base != "file")
    b.fail("base", "must be circle (2D), sphere (3D) or file (3D surface), got '" + s.base + "'");
  if ((s.base == "circle") != (s.dim == 2))
    b.fail("base", "circle needs dim 2; sphere and file need dim 3");
  if (s.base == "file") {
    std::filesystem::path p = b.text("base_file");
    if (p.is_relative()) p = std::filesystem::path(base_dir) / p;
    s.base_file = p.lexically_normal().string();
    if (!std::filesystem::exists(s.base_file))
      b.fail("base_file", "no such file: " + s.base_file);
  } else if (b.has("base_file")) {
    b.fail("base_file", "only allowed with base: file");
  }
  const YAML::Node steps = b.get("steps");
  if (!steps || !steps.IsSequence() || steps.size() == 0)
    b.fail("steps", "must be a non-empty list of [sigma, m] pairs");
  for (std::size_t k = 0; k < steps.size(); ++k) {
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
  s.dirichlet_radius = b.number("dirichlet_radius");
  if (!(s.dirichlet_radius >= 0.0 && s.dirichlet_radius <= 2.0))
    b.fail("dirichlet_radius", "must be in [0, 2] (0: no Dirichlet patch)");
  optional_number("max_turn_deg", s.max_turn_deg, 2.0, 45.0);
  optional_number("min_feature_fraction", s.min_feature_fraction, 0.0, 1.0);
  if (b.has("max_attempts")) {
    const long a = b.integer("max_attempts");
    if (a < 1 || a > 1000) b.fail("max_attempts", "must be in [1, 1000]");
    s.max_attempts = int(a);
  }
  if (b.has("quality")) {
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
  b.allowed("count, dim, base, base_file, steps, velocity_unit, nodes_per_sigma, h, dirichlet_radius, "
            "max_turn_deg, min_feature_fraction, max_attempts, quality");
  b.check_all_used();
}

}  // namespace

DatasetConfig parse_dataset_text(const std::string& text, const std::string& source,
                                 const std::string& base_dir) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw InputError(source, "", std::string("not valid YAML: ") + e.what());
  }
  if (!root || !root.IsMap()) throw InputError(source, "", "a dataset config must be a YAML mapping");
  DatasetConfig c;
  c.source = source;
  c.text = text;
  YamlBlock top(root, source, "");
  c.name = top.text("name");
  if (c.name.empty() || c.name.find_first_of("/\\ \t") != std::string::npos)
    top.fail("name", "must be a non-empty word without spaces or slashes");
  const long seed = top.integer("seed");
  if (seed < 0) top.fail("seed", "must be >= 0");
  c.seed = std::uint64_t(seed);
  if (!top.has("shapes")) top.fail("shapes", "missing (the shape family is required)");
  YamlBlock shapes(top.get("shapes"), source, "shapes");
  parse_shapes(shapes, base_dir, c.shapes, c.n_shapes);
  c.shapes.name = c.name;
  top.allowed("name, seed, shapes");
  top.check_all_used();
  return c;
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
