#include "hypershape/core/params.hpp"

#include <fmt/format.h>

#include <cmath>

#include "hypershape/core/error.hpp"

namespace hypershape::core {

double Params::number_in(const std::string& key, double lo, double hi, bool lo_open,
                         bool hi_open) const {
  const double v = number(key);
  const bool ok = (lo_open ? v > lo : v >= lo) && (hi_open ? v < hi : v <= hi);
  if (!ok)
    fail(key, fmt::format("{} is out of range; allowed: {}{}, {}{}", v, lo_open ? "(" : "[", lo,
                          hi, hi_open ? ")" : "]"));
  return v;
}

std::string list_of(std::size_t n) {
  return n ? fmt::format("a list of {} numbers", n) : std::string("a list of numbers");
}

double MapParams::number(const std::string& key) const {
  auto it = values_.find(key);
  if (it == values_.end()) fail(key, "missing (a number is required)");
  if (auto* d = std::get_if<double>(&it->second)) {
    if (!std::isfinite(*d)) fail(key, "must be a finite number");
    return *d;
  }
  throw InputError(origin_, key, "must be a number");
}

std::vector<double> MapParams::vector(const std::string& key, std::size_t n) const {
  auto it = values_.find(key);
  if (it == values_.end()) fail(key, "missing (" + list_of(n) + " is required)");
  auto* v = std::get_if<std::vector<double>>(&it->second);
  if (!v || (n ? v->size() != n : v->empty())) throw InputError(origin_, key, "must be " + list_of(n));
  return *v;
}

std::string MapParams::text(const std::string& key) const {
  auto it = values_.find(key);
  if (it == values_.end()) fail(key, "missing (a string is required)");
  auto* s = std::get_if<std::string>(&it->second);
  if (!s) throw InputError(origin_, key, "must be a string");
  return *s;
}

void MapParams::fail(const std::string& key, const std::string& message) const {
  throw InputError(origin_, key, message);
}

}  // namespace hypershape::core
