#include "hypershape/factory/dataset_scene.hpp"

#include "hypershape/core/random.hpp"

namespace hypershape::factory {

namespace {

/// A stable number for a parameter name (FNV-1a), part of its stream key.
std::uint64_t key_id(const std::string& key) {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  for (unsigned char c : key) h = (h ^ c) * 0x100000001b3ULL;
  return h;
}

std::vector<double> first(const std::array<double, 3>& v, int d) { return {v.begin(), v.begin() + d}; }

}  // namespace

double draw_parameter(const config::DatasetConfig& cfg, std::int64_t shape_id, int load_id, std::size_t effect,
                      const std::string& key, const physics::Draw& draw) {
  const std::uint64_t load = draw.per == physics::Draw::Per::load ? std::uint64_t(load_id) + 1 : 0;
  core::RandomStream rng(cfg.seed, core::Purpose::parameter,
                         {std::uint64_t(shape_id), load, std::uint64_t(effect), key_id(key)});
  return draw.at(rng.uniform());
}

std::vector<DrawnValue> drawn_values(const config::DatasetConfig& cfg, std::int64_t shape_id, int load_id) {
  std::vector<DrawnValue> out;
  for (std::size_t i = 0; i < cfg.scene.effects.size(); ++i)
    if (const auto& e = cfg.scene.effects[i]; e.count && e.copy == 0)
      out.push_back({e.name + "/count", e.count->per == physics::Draw::Per::load, double(active_copies(cfg, shape_id, load_id, i))});
  for (std::size_t i = 0; i < cfg.scene.effects.size(); ++i)
    for (const auto& [key, value] : cfg.scene.effects[i].params)
      if (const auto* d = std::get_if<physics::Draw>(&value))
        out.push_back({cfg.scene.effects[i].label + "/" + key, d->per == physics::Draw::Per::load,
                       draw_parameter(cfg, shape_id, load_id, i, key, *d)});
  return out;
}

ShapeConfig shape_config(const config::DatasetConfig& cfg, std::int64_t shape_id) {
  ShapeConfig s = cfg.shapes;
  for (auto i : cfg.scene.find("dirichlet_patch"))
    if (auto it = cfg.scene.effects[i].params.find("radius"); it != cfg.scene.effects[i].params.end())
      if (const auto* d = std::get_if<physics::Draw>(&it->second))
        s.dirichlet_radius = draw_parameter(cfg, shape_id, 0, i, "radius", *d);
  return s;
}

int active_copies(const config::DatasetConfig& cfg, std::int64_t shape_id, int load_id, std::size_t effect) {
  const auto& e = cfg.scene.effects[effect];
  if (!e.count) return 1;
  return int(draw_parameter(cfg, shape_id, load_id, effect - std::size_t(e.copy), "count", *e.count));
}

int n_tractions(const config::DatasetConfig& cfg) { return int(cfg.scene.find("gaussian_traction").size()); }

std::vector<physics::ResolvedEffect> resolve_scene(const config::DatasetConfig& cfg, const ShapeSample& shape,
                                                   const LoadCase& lc) {
  const int d = cfg.shapes.dim;
  const auto tractions = cfg.scene.find("gaussian_traction");
  auto draw = [&](std::size_t i, const std::string& key, const physics::Draw& dr) {
    return draw_parameter(cfg, shape.shape_id, lc.load_id, i, key, dr);
  };
  auto placements = [&](std::size_t i, physics::EffectParams& p) {
    const auto& e = cfg.scene.effects[i];
    if ((e.params.count("E_cv") || e.params.count("inclusions")) && !e.params.count("E_seed"))  // a modulus field: its modes per shape
      p.set("E_seed", double(core::stream_key(cfg.seed, core::Purpose::material, {std::uint64_t(shape.shape_id), i}) >> 12));
    if (e.name == "dirichlet_patch") {
      p.set("center", first(shape.dirichlet_center, d));
      p.set("radius", shape.dirichlet_radius);  // drawn per shape, before meshing
    }
    const auto k = std::size_t(std::find(tractions.begin(), tractions.end(), i) - tractions.begin());
    if (k == tractions.size()) return;
    if (!e.params.count("center")) p.set("center", first(k == 0 ? lc.center : lc.more_centers.at(k - 1), d));
    if (!e.params.count("direction"))
      p.set("direction", first(k == 0 ? lc.direction : lc.more_directions.at(k - 1), d));
  };
  auto out = physics::resolve(cfg.scene, draw, placements);
  for (std::size_t i = 0; i < out.size(); ++i)
    out[i].active = cfg.scene.effects[i].copy < active_copies(cfg, shape.shape_id, lc.load_id, i);
  return out;
}

void ShapeProblem::set_load_case(const config::DatasetConfig& cfg, const ShapeSample& shape, const LoadCase& lc) {
  const auto resolved = resolve_scene(cfg, shape, lc);
  for (std::size_t i = 0; i < resolved.size(); ++i)
    if (problem->effects()[i]->has_load()) problem->replace_load(i, physics::build_effect(resolved[i], cfg.shapes.dim));
  problem->reassemble_load();
}

ShapeProblem make_shape_problem(MPI_Comm group, const config::DatasetConfig& cfg, const ShapeSample& shape,
                                const LoadCase& first_case, std::optional<physics::SpaceOptions> space) {
  ShapeProblem out;
  out.problem = physics::build_problem(group, shape.mesh, cfg.source, resolve_scene(cfg, shape, first_case),
                                       cfg.shapes.dim, space.value_or(physics::SpaceOptions{cfg.degree, cfg.quadrature}), true);
  return out;
}

}  // namespace hypershape::factory
