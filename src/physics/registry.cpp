#include "hypershape/physics/registry.hpp"

#include <map>
#include <mutex>

#include "hypershape/core/error.hpp"

namespace hypershape::physics {

namespace {

struct Entry {
  EffectFactory factory;
  std::string help;
};

std::map<std::string, Entry>& table() {
  static std::map<std::string, Entry> t;
  return t;
}

/// The built-in effects: one line each.
void register_builtin() {
  static std::once_flag once;
  std::call_once(once, [] {
    register_neo_hookean();
    register_dirichlet_patch();
    register_gaussian_traction();
    register_body_force();
    register_saint_venant_kirchhoff();
    register_mooney_rivlin();
    register_linear_elastic();
    register_pressure();
    register_uniform_traction();
    register_dirichlet_region();
    register_spring();
  });
}

}  // namespace

void register_effect(const std::string& name, EffectFactory factory, const std::string& help) {
  table()[name] = {std::move(factory), help};
}

bool is_registered(const std::string& name) {
  register_builtin();
  return table().count(name) > 0;
}

EffectPtr make_effect(const std::string& name, const core::Params& params, int dim) {
  register_builtin();
  auto it = table().find(name);
  if (it == table().end()) {
    std::string known;
    for (auto& [n, e] : table()) known += (known.empty() ? "" : ", ") + n;
    params.fail("", "unknown effect '" + name + "'; known effects: " + known);
  }
  return it->second.factory(params, dim);
}

std::vector<std::pair<std::string, std::string>> registered_effects() {
  register_builtin();
  std::vector<std::pair<std::string, std::string>> out;
  for (auto& [n, e] : table()) out.emplace_back(n, e.help);
  return out;
}

}  // namespace hypershape::physics
