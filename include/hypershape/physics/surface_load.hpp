#pragma once
/// A dead surface load: t(x, N) per unit reference area on the Neumann facets a predicate
/// selects (N: the facet's outward unit normal in the reference configuration), integrated with
/// the space's facet rule. The traction effects (surface tractions, pressure) are instances
/// with their own name and input channel.
#include <string>

#include "hypershape/physics/effect.hpp"

namespace hypershape::physics {

/// t(x, N): writes dim components.
using FacetLoad = std::function<void(const double* x, const double* normal, double* t)>;

/// The input channel a load brings: its name ("" for none), components (0: dim) and value.
struct LoadChannel {
  std::string name;
  int components = 0;
  VectorFunction value;
};

class SurfaceLoad : public Effect {
 public:
  SurfaceLoad(std::string name, FacetLoad load, FacetPredicate select, LoadChannel channel = {})
      : name_(std::move(name)), load_(std::move(load)), select_(std::move(select)), channel_(std::move(channel)) {}
  std::string name() const override { return name_; }
  bool has_load() const override { return true; }
  void add_load(const Space& s, PetscScalar* f) const override;
  std::string channel() const override { return channel_.name; }
  int channel_components(int dim) const override { return channel_.components ? channel_.components : dim; }
  bool channel_on_boundary() const override { return true; }
  void channel_value(const double* x, double* v) const override { channel_.value(x, v); }

 private:
  std::string name_;
  FacetLoad load_;
  FacetPredicate select_;
  LoadChannel channel_;
};

}  // namespace hypershape::physics
