#pragma once
/// A problem = a mesh, a discrete space and the effects of a scene. Assembles, on global
/// vectors, R(u) = f_int(u) - s f_ext - f_fixed (s: the load factor, alpha for the Gaussian
/// traction; f_fixed: the loads of effects that are not scaled, e.g. gravity under a tuned
/// traction, assembled only when a scene has one), its tangent, and the potential energy
/// Pi(u) = int W(F) - (s f_ext + f_fixed) . u.
/// A follower load (Effect::follower(), e.g. `pressure` with `follower: true`) adds its force at
/// the state, s f_s(u) + f_f(u), to the load: the tangent then has the non-symmetric load
/// stiffness -s df_s/du - df_f/du and the problem has no energy (conservative() is false; energy()
/// still rejects states with det F <= 0 but is no potential).
#include <array>
#include <memory>
#include <vector>

#include "hypershape/core/petsc_handle.hpp"
#include "hypershape/mesh/mesh_data.hpp"
#include "hypershape/physics/effect.hpp"
#include "hypershape/physics/space.hpp"

namespace hypershape::core {
class LocalArray;
}

namespace hypershape::physics {

/// Nodal values gathered on rank 0 in canonical node order (vertices of the input mesh first,
/// then, for P2, the edge midpoints).
struct NodalField {
  int n_components = 0;
  std::vector<double> values;  ///< n_nodes x n_components, rank 0 only
};

/// Total forces and moments (about the origin) on the body at a state u and load factor s.
/// Moments are 3-vectors; in 2D only the z component (x F_y - y F_x) is non-zero.
///
/// The support force at a constrained dof is what the residual leaves there: the internal force
/// minus the applied load, (f_int(u) - s f_ext)_k, k constrained. The applied force is
/// s sum_a f_ext_a = s int t dS_0 (the facet rule of the load), the applied moment
/// s sum_a (x_a + u_a) x f_ext_a = s int (x + u) x t dS_0: dead loads act where the material
/// point is now. With every dof, sum_a f_int_a = 0 and sum_a (x_a + u_a) x f_int_a = 0 hold
/// exactly for any u (translation invariance; frame indifference, tau = P F^T symmetric, and
/// x + u_h lies in the discrete space). An elastic support (a spring: an energy that is not the
/// material's) is an external force -K u on the body: spring_force = -sum_a (K u)_a over every
/// dof (constrained ones too; the support force at a constrained dof is what is left after it).
/// So
///   reaction_force + spring_force + applied_force = -sum_free r_k,
///   reaction_moment + spring_moment + applied_moment = -sum_free (x + u)_k x r_k,
/// with r the free-dof residual: both vanish at equilibrium. The moment in the reference
/// positions, s int x x t dS_0, differs by s int u x t dS_0 and does not balance.
struct Resultants {
  bool admissible = true;                   ///< false if det F <= 0 somewhere (then garbage)
  std::array<double, 3> reaction_force{};   ///< exerted on the body by the essential conditions
  std::array<double, 3> reaction_moment{};  ///< sum over constrained dofs of (x + u) x force
  std::array<double, 3> applied_force{};    ///< s int t dS_0 (+ the fixed loads)
  std::array<double, 3> applied_moment{};   ///< s int (x + u) x t dS_0 (deformed positions)
  std::array<double, 3> applied_moment_reference{};  ///< s int x x t dS_0 (reference positions)
  std::array<double, 3> spring_force{};     ///< exerted on the body by elastic supports (springs)
  std::array<double, 3> spring_moment{};    ///< sum over dofs of (x + u) x spring force
};

class Problem {
 public:
  /// `mesh` is read on rank 0 of `comm`. Builds the plex, lets each effect mark its facets,
  /// distributes (METIS) over `comm`, builds the space and the nominal load. Collective.
  Problem(MPI_Comm comm, const mesh::MeshData& mesh, std::vector<EffectPtr> effects,
          const SpaceOptions& opt);

  const Space& space() const { return *space_; }
  DM dm() const { return space_->dm(); }
  MPI_Comm comm() const { return space_->comm(); }
  const std::vector<EffectPtr>& effects() const { return effects_; }
  /// The nominal external load f_ext, the part the load factor scales (global vector), at u = 0
  /// (a scaled follower load counted with its force at rest).
  Vec load() const { return nominal_ ? nominal_.get() : load_.get(); }
  /// -dR/ds at the state u: f_ext + f_s(u); without a scaled follower load, load() itself. The
  /// vector returned is kept by the problem and overwritten by the next call. Collective.
  Vec load_at(Vec u) const;
  /// False where some effect is a follower load: no energy, a non-symmetric tangent (LU, not
  /// LDL^T), no energy line search, no branch switching.
  bool conservative() const { return !has_follower_; }
  double load_norm() const { return load_norm_; }
  /// The fixed load f_fixed (global vector), or null when no effect has one.
  Vec fixed_load() const { return fixed_load_.get(); }
  /// True where an active effect loads the body without the load factor (a dead or follower load
  /// with scale: fixed): then u = 0 is not an equilibrium at s = 0.
  bool has_fixed_load() const;
  /// Re-runs the set-up of the load effects and reassembles f_ext and f_fixed, after a load effect was
  /// changed (e.g. GaussianTraction::set for the next load case). Collective.
  void reassemble_load();
  /// Replaces load effect `index` (of effects(); a load without energy or constraints) by
  /// `effect`, e.g. the next load case's; call reassemble_load() before use. Not collective.
  void replace_load(std::size_t index, EffectPtr effect);

  /// Each returns false (on every rank) if u has det F <= 0 at some quadrature point. Collective.
  /// `internal` (if given): the stored energy alone, the part energy_from_internal adds the
  /// loads' work to.
  bool energy(Vec u, double load_factor, double& value, double* internal = nullptr) const;
  /// The energy at u from its stored part `internal` (as energy() returned it at this u): the
  /// same number, without the cells. Collective.
  double energy_from_internal(Vec u, double load_factor, double internal) const;
  /// A merit function on the segment from `from` to `to` for line searches: energy(to) when the
  /// problem is conservative; with a follower load (no energy), the conservative part's energy at
  /// `to` minus the follower loads' work along the segment, int_0^1 f(from + t d) . d dt, d = to -
  /// from (Simpson's rule: exact for the 2D load, linear in u, and the 3D one, quadratic). Its
  /// derivative along the segment is R . d, as the energy's is. False if `to` is inadmissible.
  bool energy_along(Vec from, Vec to, double load_factor, double& value) const;
  bool residual(Vec u, double load_factor, Vec r) const;
  /// energy() and residual() in one pass over the cells (a line search's trial): the same
  /// numbers; `r` is left untouched where u is inadmissible. Not with a follower load.
  /// `internal_force` (if given): the stored energy's gradient alone, the part
  /// residual_from_internal subtracts the loads from.
  bool energy_residual(Vec u, double load_factor, double& value, Vec r, double* internal = nullptr,
                       Vec internal_force = nullptr) const;
  /// The residual at u from its `internal_force` (as energy_residual gave it at this u): the same
  /// numbers as residual(), without the cells. Not with a follower load. Collective.
  void residual_from_internal(Vec internal_force, double load_factor, Vec r) const;
  /// `load_factor` matters only for a scaled follower load (its load stiffness is s df_s/du).
  bool jacobian(Vec u, Mat J, double load_factor = 0.0) const;
  /// The same residual (load factor 0) and tangent through PETSc's generic pointwise assembly
  /// (PetscDS), for cross-checks and timings. Collective.
  void residual_pointwise(Vec u, Vec r) const;
  void jacobian_pointwise(Vec u, Mat J) const;

  /// Reaction of the essential conditions, force of the elastic supports and resultant of the
  /// load s f_ext at the state u (global vector), reduced over the communicator: every rank gets
  /// the totals. Collective.
  Resultants resultants(Vec u, double load_factor) const;

  /// max over nodes of |u| (collective).
  double max_displacement(Vec u) const;
  /// min over quadrature points of det F (collective); <= 0 means inverted.
  double min_det_f(Vec u) const;
  /// Gathers u on rank 0 in canonical node order (collective).
  NodalField gather(Vec u) const;
  /// The inverse of gather: a global vector whose owned nodes take `values` (rank 0's, canonical
  /// node order, n_nodes x dim; other ranks' ignored); constrained dofs drop out. Collective.
  core::VecH scatter(std::vector<double> values) const;
  /// Matrix with the preallocated sparsity of the tangent (symmetric flag set if conservative()).
  core::MatH create_matrix() const;
  core::VecH create_vector() const;

 private:
  /// Global -> local with the essential values inserted.
  void to_local(Vec u, Vec ul) const;
  /// The global residual from the local array of the cells' sums: minus the loads.
  void finish_residual(core::LocalArray& rl, double load_factor, Vec r, Vec internal_force = nullptr) const;
  /// Zeroes J before an assembly: all of it, or under a CellSubset the entries its cells add to.
  void zero_tangent(Mat J) const;
  /// r -= load_factor f_ext + f_fixed.
  void subtract_loads(double load_factor, Vec r) const;
  void assemble_load();
  /// Assembles the loads of the effects with scaled() == `scaled` into `f` (global).
  void assemble_loads(bool scaled, Vec f) const;
  std::vector<EffectPtr> effects_;
  std::unique_ptr<Space> space_;
  /// Adds -(s f_s(u) + f_f(u)) of the follower loads into the local residual array `r`.
  void add_follower_loads(const PetscScalar* u, double load_factor, PetscScalar* r) const;
  /// Adds w_s f_s(u) + w_f f_f(u) (scaled and fixed follower loads at the state u) into the global f.
  void add_follower_force(Vec u, double scaled_weight, double fixed_weight, Vec f) const;
  mutable core::VecH along_[3];  ///< energy_along's work vectors
  core::VecH load_, fixed_load_;
  core::VecH nominal_;          ///< f_ext + f_s(0), only with a scaled follower load
  mutable core::VecH load_at_;  ///< load_at()'s result
  bool has_follower_ = false, has_scaled_follower_ = false;
  double load_norm_ = 0;
  mutable core::MatH pattern_;  ///< the tangent's pattern, from the DM once (create_matrix)
};

}  // namespace hypershape::physics
