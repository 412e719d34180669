#pragma once
/// Effects: the self-contained pieces a scene is assembled from. A scene lists its effects and
/// only those are assembled. An effect may
///   - mark boundary facets and impose homogeneous essential conditions on them (Dirichlet),
///   - contribute a stored energy with its residual and tangent (a material),
///   - contribute a dead load, a fixed external force vector (tractions, body forces), either
///     scaled by the problem's load factor (the default: alpha, tuned to a target max|u|) or
///     applied as it is (set_scaled(false): e.g. gravity under a tuned traction).
/// A new effect is one file that implements this interface plus one line in registry.cpp.
#include <petscdm.h>
#include <petscds.h>
#include <petscmat.h>

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "hypershape/core/params.hpp"
#include "hypershape/physics/space.hpp"

namespace hypershape::physics {

class Effect {
 public:
  virtual ~Effect() = default;
  virtual std::string name() const = 0;

  // ---- constraints ---------------------------------------------------------------------------
  /// Labels the facets this effect constrains on the serial plex (every point on rank 0), before
  /// distribution. Collective over the plex's communicator.
  virtual void mark(DM /*serial*/) {}
  virtual std::vector<EssentialBC> essential_bcs() const { return {}; }

  // ---- set-up once the space exists ----------------------------------------------------------
  /// Collective.
  virtual void setup(const Space& /*space*/) {}

  // ---- stored energy (materials) -------------------------------------------------------------
  virtual bool has_energy() const { return false; }
  /// Whether the energy is the body's material (a scene has exactly one); an elastic support
  /// (spring) has an energy but is not a material.
  virtual bool is_material() const { return has_energy(); }
  /// Whether the effect restrains the body (a scene needs at least one): essential conditions,
  /// or a spring foundation.
  virtual bool is_support() const { return !essential_bcs().empty(); }
  /// Each adds over the local cells; `u` and `r` are local-vector arrays. Each returns false,
  /// leaving partial sums, if some quadrature point has det F <= 0 (not collective).
  virtual bool add_energy(const Space&, const PetscScalar* /*u*/, double& /*energy*/) const {
    return true;
  }
  virtual bool add_residual(const Space&, const PetscScalar* /*u*/, PetscScalar* /*r*/) const {
    return true;
  }
  virtual bool add_jacobian(const Space&, const PetscScalar* /*u*/, Mat /*J*/) const {
    return true;
  }
  /// add_energy and add_residual in one pass (a line search's trial needs both): the same sums
  /// in the same order; a material overrides it to share the kinematics of its cells.
  virtual bool add_energy_residual(const Space& s, const PetscScalar* u, double& energy, PetscScalar* r) const {
    return add_energy(s, u, energy) && add_residual(s, u, r);
  }
  /// Registers the same physics as PETSc pointwise functions (generic assembly, cross-checks).
  virtual void set_pointwise(PetscDS /*ds*/) const {}

  // ---- dead loads -----------------------------------------------------------------------------
  virtual bool has_load() const { return false; }
  /// Adds the nominal external force into the local-vector array `f`. Not collective.
  virtual void add_load(const Space&, PetscScalar* /*f*/) const {}

  // ---- follower loads (configuration-dependent) ------------------------------------------------
  /// A load that follows the deformation (a pressure on the deformed surface, Nanson's
  /// n da = J F^-T N dA): its force depends on u and has no potential in general, so its tangent
  /// is not symmetric. It is a load (has_load(), scaled() as any other), but the Problem assembles
  /// it at the state through the two functions below, never as a fixed vector (add_load is the
  /// force at u = 0, for channels and the nominal load's norm).
  virtual bool follower() const { return false; }
  /// Adds scale times the force at the state u (local-vector arrays) into `f`. Not collective.
  virtual void add_follower_load(const Space&, const PetscScalar* /*u*/, double /*scale*/, PetscScalar* /*f*/) const {}
  /// Adds -scale times its derivative (the load stiffness: the residual is f_int - f) into J.
  virtual void add_follower_jacobian(const Space&, const PetscScalar* /*u*/, double /*scale*/, Mat /*J*/) const {}

  // ---- input channels (what a dataset stores of the effect) ----------------------------------
  /// The model-input field the effect brings ("traction", "body_force"), "" for none. A dataset
  /// stores each channel at the nodes and on the grid; effects of one channel are summed.
  virtual std::string channel() const { return ""; }
  /// Components of the channel in a problem of dimension `dim` (a vector field: dim).
  virtual int channel_components(int dim) const { return dim; }
  /// True for a surface field: stored at the Neumann boundary nodes only (zero elsewhere).
  virtual bool channel_on_boundary() const { return false; }
  /// The field at x for load factor 1 (channel_components() values). Valid after setup(). Not
  /// collective. A material's channel (a modulus field) is not scaled by the load factor.
  virtual void channel_value(const double* /*x*/, double* /*value*/) const {}

  /// Whether the load factor scales this effect's load (f_ext) or it is fixed (f_fixed).
  bool scaled() const { return scaled_; }
  void set_scaled(bool scaled) { scaled_ = scaled; }
  /// An inactive load contributes nothing (a copy beyond the count drawn for this load case).
  bool active() const { return active_; }
  void set_active(bool active) { active_ = active; }

 private:
  bool scaled_ = true;
  bool active_ = true;
};

using EffectPtr = std::unique_ptr<Effect>;
/// Builds an effect from its validated parameters for a problem of dimension `dim`.
using EffectFactory = std::function<EffectPtr(const core::Params& params, int dim)>;

/// Adds an effect to the registry (`help` is a one-line description with its keys).
void register_effect(const std::string& name, EffectFactory factory, const std::string& help);
/// Builds a registered effect; throws core::InputError (via params.fail) for unknown names.
EffectPtr make_effect(const std::string& name, const core::Params& params, int dim);
bool is_registered(const std::string& name);
/// Registered names with their help lines, sorted by name.
std::vector<std::pair<std::string, std::string>> registered_effects();

// ---- effects built in C++ (verification problems, tests) ------------------------------------

/// Selects boundary facets by the coordinates of their vertices (n_vertices x dim, row-major).
using FacetPredicate = std::function<bool(const double* vertex_coords, int n_vertices, int dim)>;
/// A scalar field of the reference position (e.g. a modulus factor m(x) > 0).
using ScalarFunction = std::function<double(const double* x)>;
/// Traction t(x) per unit reference area (first Piola), writes dim components.
using VectorFunction = std::function<void(const double* x, double* value)>;

/// Homogeneous Dirichlet condition on the boundary facets selected by `select`, fixing
/// `components` (all when empty). Each instance creates its own label `label_name`.
EffectPtr make_dirichlet(std::string label_name, FacetPredicate select,
                         std::vector<PetscInt> components = {});
/// Dead surface traction t(x) on the Neumann facets selected by `select` (all when empty).
EffectPtr make_surface_traction(VectorFunction traction, FacetPredicate select = {});
/// Dead body force b(x) per unit reference volume.
EffectPtr make_body_force(VectorFunction force, int quadrature_degree = 0);

}  // namespace hypershape::physics
