#pragma once
/// A problem = a mesh, a discrete space and the effects of a scene. Assembles, on global
/// vectors, R(u) = f_int(u) - s f_ext (s: the load factor, alpha for the Gaussian traction),
/// its tangent, and the potential energy Pi(u) = int W(F) - s f_ext . u.
#include <memory>
#include <vector>

#include "hypershape/core/petsc_handle.hpp"
#include "hypershape/mesh/mesh_data.hpp"
#include "hypershape/physics/effect.hpp"
#include "hypershape/physics/space.hpp"

namespace hypershape::physics {

/// Nodal values gathered on rank 0 in canonical node order (vertices of the input mesh first,
/// then, for P2, the edge midpoints).
struct NodalField {
  int n_components = 0;
  std::vector<double> values;  ///< n_nodes x n_components, rank 0 only
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
  /// The nominal external load f_ext (global vector).
  Vec load() const { return load_.get(); }
  double load_norm() const { return load_norm_; }
  /// Re-runs the set-up of the load effects and reassembles f_ext, after a load effect was
  /// changed (e.g. GaussianTraction::set for the next load case). Collective.
  void reassemble_load();

  /// Each returns false (on every rank) if u has det F <= 0 at some quadrature point. Collective.
  bool energy(Vec u, double load_factor, double& value) const;
  bool residual(Vec u, double load_factor, Vec r) const;
  bool jacobian(Vec u, Mat J) const;
  /// The same residual (load factor 0) and tangent through PETSc's generic pointwise assembly
  /// (PetscDS), for cross-checks and timings. Collective.
  void residual_pointwise(Vec u, Vec r) const;
  void jacobian_pointwise(Vec u, Mat J) const;

  /// max over nodes of |u| (collective).
  double max_displacement(Vec u) const;
  /// min over quadrature points of det F (collective); <= 0 means inverted.
  double min_det_f(Vec u) const;
  /// Gathers u on rank 0 in canonical node order (collective).
  NodalField gather(Vec u) const;
  /// Matrix with the preallocated sparsity of the tangent (symmetric flag set).
  core::MatH create_matrix() const;
  core::VecH create_vector() const;

 private:
  /// Global -> local with the essential values inserted.
  void to_local(Vec u, Vec ul) const;
  void assemble_load();
  std::vector<EffectPtr> effects_;
  std::unique_ptr<Space> space_;
  core::VecH load_;
  double load_norm_ = 0;
};

}  // namespace hypershape::physics
