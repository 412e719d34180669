#include "hypershape/physics/region.hpp"

#include <algorithm>
#include <cmath>

namespace hypershape::physics {

Region Region::box(std::vector<double> lower, std::vector<double> upper) {
  Region r;
  r.kind_ = Kind::box;
  double size = 1e-300;
  for (std::size_t k = 0; k < lower.size(); ++k) size = std::max(size, std::abs(upper[k] - lower[k]));
  for (std::size_t k = 0; k < lower.size(); ++k) size = std::max({size, std::abs(lower[k]), std::abs(upper[k])});
  r.tol_ = 1e-9 * size;
  r.a_ = std::move(lower);
  r.b_ = std::move(upper);
  return r;
}

Region Region::ball(std::vector<double> center, double radius) {
  Region r;
  r.kind_ = Kind::ball;
  r.tol_ = 1e-9 * std::max(1.0, radius);
  r.a_ = std::move(center);
  r.b_ = {radius};
  return r;
}

Region Region::from_params(const core::Params& p, int dim, bool required) {
  const bool has_box = p.has("box"), has_ball = p.has("center") || p.has("radius");
  if (has_box && has_ball) p.fail("box", "give either box or center + radius, not both");
  if (has_box) {
    const auto v = p.vector("box", std::size_t(2 * dim));
    std::vector<double> lo(v.begin(), v.begin() + dim), hi(v.begin() + dim, v.end());
    for (int k = 0; k < dim; ++k)
      if (!(lo[std::size_t(k)] <= hi[std::size_t(k)]))
        p.fail("box", "must be [lower corner, upper corner] with lower <= upper in every coordinate");
    return box(std::move(lo), std::move(hi));
  }
  if (has_ball) return ball(p.vector("center", std::size_t(dim)), p.number_in("radius", 0.0, 1e300, true));
  if (required) p.fail("box", "missing: give the region, box: [lower corner, upper corner] or center + radius");
  return {};
}

bool Region::contains(const double* x, int dim) const {
  if (kind_ == Kind::all) return true;
  if (kind_ == Kind::box) {
    for (int k = 0; k < dim; ++k)
      if (x[k] < a_[std::size_t(k)] - tol_ || x[k] > b_[std::size_t(k)] + tol_) return false;
    return true;
  }
  double d2 = 0;
  for (int k = 0; k < dim; ++k) d2 += (x[k] - a_[std::size_t(k)]) * (x[k] - a_[std::size_t(k)]);
  return std::sqrt(d2) <= b_[0] + tol_;
}

FacetPredicate Region::facets() const {
  return [r = *this](const double* x, int nv, int dim) {
    for (int a = 0; a < nv; ++a)
      if (!r.contains(x + a * dim, dim)) return false;
    return true;
  };
}

const char* region_help() {
  return "region: box [lower corner, upper corner] or center + radius (default: the whole free boundary)";
}

}  // namespace hypershape::physics
