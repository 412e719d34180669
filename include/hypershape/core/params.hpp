#pragma once
/// A read-only view of one block of user parameters (an effect's keys in a scene file, say).
/// Implemented by config/ on top of YAML and by core::MapParams for programmatic use, so that
/// physics code can validate its own parameters without knowing the file format.
#include <map>
#include <string>
#include <variant>
#include <vector>

namespace hypershape::core {

class Params {
 public:
  virtual ~Params() = default;
  virtual bool has(const std::string& key) const = 0;
  /// A finite number; throws InputError naming the file and key if missing or not a number.
  virtual double number(const std::string& key) const = 0;
  /// A list of exactly `n` finite numbers (n = 0: of any length >= 1).
  virtual std::vector<double> vector(const std::string& key, std::size_t n) const = 0;
  virtual std::string text(const std::string& key) const = 0;
  /// Throws InputError naming the file and this block's `key`.
  [[noreturn]] virtual void fail(const std::string& key, const std::string& message) const = 0;

  double number_or(const std::string& key, double fallback) const {
    return has(key) ? number(key) : fallback;
  }
  /// A number in (lo, hi) or [lo, hi] depending on the flags; the message states the range.
  double number_in(const std::string& key, double lo, double hi, bool lo_open = false,
                   bool hi_open = false) const;
};

/// "a list of n numbers" (n = 0: "a list of numbers"), for messages.
std::string list_of(std::size_t n);

/// Params held in memory (tests, benchmarks, programmatic scenes). `fail` reports `origin`.
class MapParams : public Params {
 public:
  using Value = std::variant<double, std::vector<double>, std::string>;
  explicit MapParams(std::map<std::string, Value> values = {}, std::string origin = "<memory>")
      : values_(std::move(values)), origin_(std::move(origin)) {}
  MapParams& set(const std::string& key, Value v) {
    values_[key] = std::move(v);
    return *this;
  }
  bool has(const std::string& key) const override { return values_.count(key) > 0; }
  double number(const std::string& key) const override;
  std::vector<double> vector(const std::string& key, std::size_t n) const override;
  std::string text(const std::string& key) const override;
  [[noreturn]] void fail(const std::string& key, const std::string& message) const override;

 private:
  std::map<std::string, Value> values_;
  std::string origin_;
};

}  // namespace hypershape::core
