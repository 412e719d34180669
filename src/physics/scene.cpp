#include "hypershape/physics/scene.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "hypershape/core/error.hpp"
#include "hypershape/physics/registry.hpp"

namespace hypershape::physics {

// ---- Draw ------------------------------------------------------------------------------------

double Draw::at(double u) const {
  switch (kind) {
    case Kind::uniform: return values[0] + (values[1] - values[0]) * u;
    case Kind::log_uniform: return values[0] * std::pow(values[1] / values[0], u);
    case Kind::choice: {
      const auto n = values.size();
      return values[std::min(n - 1, std::size_t(u * double(n)))];
    }
  }
  return values[0];
}

double Draw::low() const { return *std::min_element(values.begin(), values.end()); }
double Draw::high() const { return *std::max_element(values.begin(), values.end()); }

std::string Draw::describe() const {
  const char* k = kind == Kind::uniform ? "uniform" : kind == Kind::log_uniform ? "log_uniform" : "choice";
  return fmt::format("{} [{}] per {}", k, fmt::join(values, ", "), per == Per::shape ? "shape" : "load");
}

std::vector<std::size_t> SceneSpec::find(const std::string& name) const {
  std::vector<std::size_t> out;
  for (std::size_t i = 0; i < effects.size(); ++i)
    if (effects[i].name == name) out.push_back(i);
  return out;
}

// ---- EffectParams ----------------------------------------------------------------------------

bool EffectParams::has(const std::string& key) const {
  used_.insert(key);
  return values_.count(key) > 0;
}

double EffectParams::number(const std::string& key) const {
  used_.insert(key);
  auto it = values_.find(key);
  if (it == values_.end()) fail(key, "missing (a number is required)");
  const double* d = std::get_if<double>(&it->second);
  if (!d) fail(key, "must be a number");
  if (!std::isfinite(*d)) fail(key, "must be a finite number");
  return *d;
}

std::vector<double> EffectParams::vector(const std::string& key, std::size_t n) const {
  used_.insert(key);
  auto it = values_.find(key);
  if (it == values_.end()) fail(key, "missing (" + core::list_of(n) + " is required)");
  auto* v = std::get_if<std::vector<double>>(&it->second);
  if (!v || (n ? v->size() != n : v->empty())) fail(key, "must be " + core::list_of(n));
  return *v;
}

std::string EffectParams::text(const std::string& key) const {
  used_.insert(key);
  auto it = values_.find(key);
  if (it == values_.end()) fail(key, "missing (a string is required)");
  auto* s = std::get_if<std::string>(&it->second);
  if (!s) fail(key, "must be a string");
  return *s;
}

void EffectParams::fail(const std::string& key, const std::string& message) const {
  throw core::InputError(file_, key.empty() ? path_ : path_ + "." + key, message);
}

void EffectParams::check_all_used() const {
  for (const auto& [k, v] : values_)
    if (!used_.count(k)) fail(k, "unknown key for this effect");
}

// ---- resolve and build -------------------------------------------------------------------------

std::vector<ResolvedEffect> resolve(const SceneSpec& spec, const DrawFn& draw,
                                    const std::function<void(std::size_t, EffectParams&)>& extra) {
  std::vector<ResolvedEffect> out;
  for (std::size_t i = 0; i < spec.effects.size(); ++i) {
    const EffectSpec& e = spec.effects[i];
    ResolvedEffect r{e.name, EffectParams(spec.source, e.path), e.scaled, e.scale_given};
    for (const auto& [key, value] : e.params) {
      if (const auto* d = std::get_if<Draw>(&value)) r.params.set(key, draw(i, key, *d));
      else std::visit([&](const auto& v) {
        if constexpr (!std::is_same_v<std::decay_t<decltype(v)>, Draw>) r.params.set(key, v);
      }, value);
    }
    if (extra) extra(i, r.params);
    out.push_back(std::move(r));
  }
  return out;
}

EffectPtr build_effect(const ResolvedEffect& r, int dim) {
  EffectPtr e = make_effect(r.name, r.params, dim);
  r.params.check_all_used();
  if (r.scale_given && !e->has_load())
    r.params.fail("scale", "only a load (a traction, a body force) has a scale");
  e->set_scaled(r.scaled);
  e->set_active(r.active);
  return e;
}

std::vector<EffectPtr> build_effects(const std::string& source, const std::vector<ResolvedEffect>& effects,
                                     int dim, bool needs_scaled_load) {
  std::vector<EffectPtr> out;
  std::string material;
  bool dirichlet = false, scaled_load = false;
  for (const ResolvedEffect& r : effects) {
    EffectPtr e = build_effect(r, dim);
    if (e->is_material()) {
      if (!material.empty())
        r.params.fail("", "a second material (" + material + " is one): one material per body "
                          "(materials by region are not supported)");
      material = r.name;
    }
    dirichlet = dirichlet || e->is_support() || r.name.find("dirichlet") != std::string::npos;
    scaled_load = scaled_load || (e->has_load() && e->scaled());
    out.push_back(std::move(e));
  }
  if (material.empty())
    throw core::InputError(source, "effects", "no material: add one, e.g. neo_hookean: {E: 500, nu: 0.49}");
  if (!dirichlet)
    throw core::InputError(source, "effects",
                           "no Dirichlet condition (e.g. dirichlet_patch): the problem would be singular");
  if (needs_scaled_load && !scaled_load)
    throw core::InputError(source, "effects",
                           "no load scaled by alpha (scale: alpha, the default): a target max|u| "
                           "tunes alpha, so at least one load must be scaled by it");
  return out;
}

std::unique_ptr<Problem> build_problem(MPI_Comm comm, const mesh::MeshData& mesh, const std::string& source,
                                       const std::vector<ResolvedEffect>& effects, int dim,
                                       const SpaceOptions& space, bool needs_scaled_load) {
  return std::make_unique<Problem>(comm, mesh, build_effects(source, effects, dim, needs_scaled_load), space);
}

}  // namespace hypershape::physics
