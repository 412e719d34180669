#include "effects_block.hpp"

#include <cmath>

#include "hypershape/config/scene.hpp"

namespace hypershape::config {

namespace {

/// A distribution: {uniform: [a, b]} | {log_uniform: [a, b]} | {choice: [...]}, + sample.
physics::Draw parse_draw(const YamlBlock& b) {
  physics::Draw d;
  int kinds = 0;
  for (auto [name, kind] : {std::pair{"uniform", physics::Draw::Kind::uniform},
                            std::pair{"log_uniform", physics::Draw::Kind::log_uniform},
                            std::pair{"choice", physics::Draw::Kind::choice}})
    if (b.has(name)) {
      ++kinds;
      d.kind = kind;
      const YAML::Node v = b.get(name);
      const std::size_t n = v.IsSequence() ? v.size() : 0;
      d.values = b.vector(name, kind == physics::Draw::Kind::choice ? std::max<std::size_t>(n, 1) : 2);
    }
  if (kinds != 1)
    b.fail("", "a distribution is one of {uniform: [a, b]}, {log_uniform: [a, b]}, {choice: [x, y, ...]}, "
               "with an optional sample: shape | load");
  const auto& v = d.values;
  if (d.kind == physics::Draw::Kind::uniform && !(v[0] <= v[1])) b.fail("uniform", "must be [a, b] with a <= b");
  if (d.kind == physics::Draw::Kind::log_uniform && !(v[0] > 0 && v[0] <= v[1]))
    b.fail("log_uniform", "must be [a, b] with 0 < a <= b");
  if (b.has("sample")) {
    const std::string s = b.text("sample");
    if (s != "shape" && s != "load") b.fail("sample", "must be shape or load, got '" + s + "'");
    d.per = s == "shape" ? physics::Draw::Per::shape : physics::Draw::Per::load;
  }
  b.allowed("uniform, log_uniform, choice, sample");
  b.check_all_used();
  return d;
}

physics::ParamValue parse_value(const YamlBlock& b, const std::string& key, bool allow_draws) {
  const YAML::Node n = b.get(key);
  if (n.IsMap()) {
    if (!allow_draws)
      b.fail(key, "must be a number here (distributions are for dataset configs: a scene file is one solve)");
    return parse_draw(YamlBlock(n, b.file(), join(b.path(), key)));
  }
  if (n.IsSequence()) return b.vector(key, n.size());
  if (!n.IsScalar()) b.fail(key, "must be a number, a list of numbers or a word");
  try {
    return b.number(key);
  } catch (const InputError&) {
    return b.text(key);  // a word (an effect decides whether it takes one)
  }
}

/// `count`: an integer >= 1 or {choice: [integers >= 1], sample: ...}, as a Draw.
physics::Draw count_draw(const YamlBlock& b, bool allow_draws) {
  physics::Draw d{physics::Draw::Kind::choice, {}, physics::Draw::Per::load};
  const physics::ParamValue v = parse_value(b, "count", allow_draws);
  if (const auto* n = std::get_if<double>(&v)) d.values = {*n}, d.per = physics::Draw::Per::shape;
  else if (const auto* c = std::get_if<physics::Draw>(&v); c && c->kind == physics::Draw::Kind::choice) d = *c;
  else b.fail("count", "must be an integer >= 1 or {choice: [integers >= 1], sample: shape | load}");
  for (double x : d.values)
    if (!(x >= 1 && x <= 100 && x == std::floor(x))) b.fail("count", "copies must be integers in [1, 100]");
  return d;
}

/// An effect with a count: copies 0..max-1 (labels name.k), each active below the count drawn.
void add_copies(physics::SceneSpec& s, const physics::EffectSpec& e) {
  const int n = int(e.count->high());
  for (int k = 0; k < n; ++k) {
    physics::EffectSpec c = e;
    c.label = e.name + "." + std::to_string(k);
    c.copy = k;
    s.effects.push_back(std::move(c));
  }
}

physics::EffectSpec parse_effect(const YAML::Node& node, const std::string& file, const std::string& name,
                                 const std::string& path, bool allow_draws) {
  physics::EffectSpec e;
  e.name = name;
  e.label = name;
  e.path = path;
  if (node && !node.IsNull() && !node.IsMap())
    throw InputError(file, path, "must be a mapping of parameters (or a list of them)");
  YamlBlock b(node, file, path);
  if (!node || node.IsNull()) return e;
  for (const auto& kv : node) {
    const std::string key = kv.first.Scalar();
    if (key == "count") {
      e.count = count_draw(b, allow_draws);
      continue;
    }
    if (key == "scale") {
      const std::string s = b.text("scale");
      if (s != "alpha" && s != "fixed") b.fail("scale", "must be alpha (scaled by the tuned load factor) or fixed");
      e.scaled = s == "alpha";
      e.scale_given = true;
      continue;
    }
    e.params[key] = parse_value(b, key, allow_draws);
  }
  return e;
}

}  // namespace

physics::SceneSpec parse_effects(const YamlBlock& block, bool allow_draws) {
  physics::SceneSpec s;
  s.source = block.file();
  if (!block.node() || !block.node().IsMap() || block.node().size() == 0)
    block.fail("", "must list at least one effect (a mapping of effect names to parameters)");
  for (const auto& kv : block.node()) {
    const std::string name = kv.first.Scalar();
    block.get(name);  // mark used; the registry checks the name when the effect is built
    const std::string path = join(block.path(), name);
    if (!kv.second.IsSequence()) {
      auto e = parse_effect(kv.second, block.file(), name, path, allow_draws);
      if (e.count) add_copies(s, e);
      else s.effects.push_back(std::move(e));
      continue;
    }
    if (kv.second.size() == 0) block.fail(name, "an empty list: give at least one entry or leave the effect out");
    for (std::size_t k = 0; k < kv.second.size(); ++k) {
      auto e = parse_effect(kv.second[k], block.file(), name, path + "[" + std::to_string(k) + "]", allow_draws);
      e.label = name + "." + std::to_string(k);
      if (e.count) block.fail(name + "[" + std::to_string(k) + "].count", "a count is for an effect given once, not in a list");
      s.effects.push_back(std::move(e));
    }
  }
  return s;
}

std::string effects_yaml(const physics::SceneSpec& spec) {
  YAML::Emitter out;
  out.SetDoublePrecision(15);  // 0.49, not 0.48999999999999999
  out << YAML::BeginMap;
  std::string open_list;
  auto close_list = [&] {
    if (!open_list.empty()) out << YAML::EndSeq;
    open_list.clear();
  };
  for (const auto& e : spec.effects) {
    if (e.count && e.copy > 0) continue;  // written once, with its count
    const bool listed = e.label != e.name && !e.count;
    if (!listed || open_list != e.name) {
      close_list();
      out << YAML::Key << e.name << YAML::Value;
      if (listed) out << YAML::BeginSeq, open_list = e.name;
    }
    out << YAML::Flow << YAML::BeginMap;
    for (const auto& [key, value] : e.params) {
      out << YAML::Key << key << YAML::Value;
      if (const auto* d = std::get_if<double>(&value)) out << *d;
      else if (const auto* v = std::get_if<std::vector<double>>(&value)) out << YAML::Flow << *v;
      else if (const auto* t = std::get_if<std::string>(&value)) out << *t;
      else {
        const auto& draw = std::get<physics::Draw>(value);
        const char* k = draw.kind == physics::Draw::Kind::uniform       ? "uniform"
                        : draw.kind == physics::Draw::Kind::log_uniform ? "log_uniform"
                                                                         : "choice";
        out << YAML::BeginMap << YAML::Key << k << YAML::Value << YAML::Flow << draw.values << YAML::Key
            << "sample" << YAML::Value << (draw.per == physics::Draw::Per::shape ? "shape" : "load")
            << YAML::EndMap;
      }
    }
    if (e.scale_given) out << YAML::Key << "scale" << YAML::Value << (e.scaled ? "alpha" : "fixed");
    if (e.count)
      out << YAML::Key << "count" << YAML::Value << YAML::BeginMap << YAML::Key << "choice" << YAML::Value
          << YAML::Flow << e.count->values << YAML::Key << "sample" << YAML::Value
          << (e.count->per == physics::Draw::Per::shape ? "shape" : "load") << YAML::EndMap;
    out << YAML::EndMap;
  }
  close_list();
  out << YAML::EndMap;
  return out.c_str();
}

}  // namespace hypershape::config
