#pragma once
/// Strict YAML reading shared by the config parsers (internal to src/config/): every key is
/// checked, and errors name the file and the dotted key path.
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "hypershape/core/input_error.hpp"

namespace hypershape::config {

using core::InputError;

inline std::string join(const std::string& a, const std::string& b) {
  return a.empty() ? b : b.empty() ? a : a + "." + b;
}

/// A number as the user would write it (0.5, 1e-3), for messages.
inline std::string fmt_number(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

/// Key checks for one YAML mapping.
class YamlBlock {
 public:
  YamlBlock(const YAML::Node& node, std::string file, std::string path)
      : node_(node), file_(std::move(file)), path_(std::move(path)) {
    if (node_ && !node_.IsNull() && !node_.IsMap())
      throw InputError(file_, path_, "must be a mapping of keys to values");
  }
  [[noreturn]] void fail(const std::string& key, const std::string& msg) const {
    throw InputError(file_, join(path_, key), msg);
  }
  bool has(const std::string& key) const {
    used_.insert(key);
    return node_ && node_.IsMap() && node_[key] && !node_[key].IsNull();
  }
  /// The value of `key` if it must be a mapping (absent: a null node); names the key otherwise.
  YAML::Node mapping(const std::string& key) const {
    auto n = get(key);
    if (n && !n.IsNull() && !n.IsMap())
      fail(key, "must be a mapping of keys to values (key: value, or {key: value}), got " +
                    std::string(n.IsScalar() ? "'" + n.Scalar() + "'" : "a list"));
    return n;
  }
  YAML::Node get(const std::string& key) const {
    used_.insert(key);
    return node_ && node_.IsMap() ? node_[key] : YAML::Node();
  }
  double number(const std::string& key) const {
    auto n = get(key);
    if (!n || n.IsNull()) fail(key, "missing (a number is required)");
    if (!n.IsScalar()) fail(key, "must be a number");
    double v;
    try {
      v = n.as<double>();
    } catch (const YAML::Exception&) {
      fail(key, "must be a number, got '" + n.Scalar() + "'");
    }
    if (!std::isfinite(v)) fail(key, "must be a finite number");
    return v;
  }
  long integer(const std::string& key) const {
    const double v = number(key);
    if (v != std::floor(v)) fail(key, "must be an integer");
    // Beyond 2^53 a double no longer holds every integer (and 1e30 overflows a long).
    if (std::abs(v) > 9007199254740992.0) fail(key, "must be an integer of magnitude at most 2^53, got " + fmt_number(v));
    return long(v);
  }
  /// An integer in [lo, hi]; the message names the range (and `unit`, e.g. "shapes per shard").
  long integer(const std::string& key, long lo, long hi, const std::string& unit = "") const {
    const long v = integer(key);
    if (v < lo || v > hi)
      fail(key, "must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]" +
                    (unit.empty() ? "" : " (" + unit + ")") + ", got " + std::to_string(v));
    return v;
  }
  bool boolean(const std::string& key) const {
    auto n = get(key);
    if (!n || n.IsNull()) fail(key, "missing (true or false is required)");
    try {
      return n.as<bool>();
    } catch (const YAML::Exception&) {
      fail(key, "must be true or false");
    }
  }
  std::string text(const std::string& key) const {
    auto n = get(key);
    if (!n || n.IsNull()) fail(key, "missing (a string is required)");
    if (!n.IsScalar()) fail(key, "must be a string");
    return n.Scalar();
  }
  std::vector<double> vector(const std::string& key, std::size_t n) const {
    auto v = get(key);
    if (!v || v.IsNull()) fail(key, "missing (a list of " + std::to_string(n) + " numbers is required)");
    if (!v.IsSequence() || v.size() != n)
      fail(key, "must be a list of " + std::to_string(n) + " numbers");
    std::vector<double> out;
    for (const auto& e : v) {
      double x;
      try {
        x = e.as<double>();
      } catch (const YAML::Exception&) {
        fail(key, "must be a list of " + std::to_string(n) + " numbers");
      }
      if (!std::isfinite(x)) fail(key, "must hold finite numbers");
      out.push_back(x);
    }
    return out;
  }
  void check_all_used() const {
    if (!node_ || !node_.IsMap()) return;
    for (const auto& kv : node_) {
      const auto k = kv.first.Scalar();
      if (!used_.count(k)) fail(k, "unknown key" + (allowed_.empty() ? "" : "; allowed: " + allowed_));
    }
  }
  void allowed(std::string a) const { allowed_ = std::move(a); }
  const YAML::Node& node() const { return node_; }
  const std::string& file() const { return file_; }
  const std::string& path() const { return path_; }

 private:
  YAML::Node node_;
  std::string file_, path_;
  mutable std::string allowed_;
  mutable std::set<std::string> used_;
};

/// Parses YAML text, rejecting what yaml-cpp lets through silently: a key given twice in a
/// mapping and a quoted string not closed on its line. Throws InputError naming `source`.
YAML::Node load_yaml(const std::string& text, const std::string& source);

}  // namespace hypershape::config
