#include <fmt/format.h>

#include "yaml_block.hpp"

namespace hypershape::config {

namespace {

/// The key text of a map entry, for paths and messages.
std::string key_text(const YAML::Node& key) { return key.IsScalar() ? key.Scalar() : "<complex key>"; }

/// Where a quoted scalar that starts at `pos` closes, or npos if not on its own line.
std::size_t closing_quote(const std::string& text, std::size_t pos) {
  const char q = text[pos];
  for (std::size_t i = pos + 1; i < text.size() && text[i] != '\n'; ++i) {
    if (q == '"' && text[i] == '\\') {
      ++i;
      continue;
    }
    if (text[i] != q) continue;
    if (q == '\'' && i + 1 < text.size() && text[i + 1] == '\'') {
      ++i;  // '' is an escaped quote inside a single-quoted string
      continue;
    }
    return i;
  }
  return std::string::npos;
}

/// Rejects what yaml-cpp accepts silently: a key given twice in one mapping (yaml-cpp keeps
/// both; the merge would take the last) and a quoted string that runs past its line (a missing
/// closing quote swallows the keys after it).
void check_node(const YAML::Node& n, const std::string& text, const std::string& source, const std::string& path) {
  if (n.IsScalar()) {
    const auto m = n.Mark();
    const auto pos = std::size_t(m.pos);
    if (m.pos >= 0 && pos < text.size() && (text[pos] == '"' || text[pos] == '\'') &&
        closing_quote(text, pos) == std::string::npos)
      throw InputError(source, path,
                       fmt::format("the quoted string at line {}, column {} is not closed on its line (a missing "
                                   "closing {} swallows the keys after it)",
                                   m.line + 1, m.column + 1, text[pos]));
  } else if (n.IsSequence()) {
    for (std::size_t i = 0; i < n.size(); ++i) check_node(n[i], text, source, path + "[" + std::to_string(i) + "]");
  } else if (n.IsMap()) {
    std::set<std::string> seen;
    for (const auto& kv : n) {
      const std::string k = key_text(kv.first);
      if (!seen.insert(k).second)
        throw InputError(source, join(path, k),
                         fmt::format("given twice (line {}): each key may appear once in a mapping",
                                     kv.first.Mark().line + 1));
      check_node(kv.second, text, source, join(path, k));
    }
  }
}

}  // namespace

YAML::Node load_yaml(const std::string& text, const std::string& source) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw InputError(source, "", std::string("not valid YAML: ") + e.what());
  }
  check_node(root, text, source, "");
  return root;
}

}  // namespace hypershape::config
