#pragma once
/// Nonlinear elimination of a local trouble spot (Cai & Keyes 2002; Hwang & Cai 2007): where the
/// residual of a Newton iterate sits on a few nodes -- the clamp's or the load's patch ends, where
/// a linearised step over-stretches a handful of cells -- the corrector's global Newton steps
/// creep, cut by the energy line search to what those cells allow. LocalRelaxation minimises the
/// energy over the dofs of a small patch around those nodes instead, everything else held, by
/// dense Newton steps on the patch (shifted where its tangent is indefinite, so that they
/// descend), before the corrector's next global step. One rank, conservative problems
/// (an energy to descend).
#include <petscmat.h>
#include <petscvec.h>

#include <Eigen/Core>
#include <vector>

#include "hypershape/core/petsc_handle.hpp"
#include "hypershape/physics/problem.hpp"

namespace hypershape::solver {

/// The global index of every local-vector entry of `problem` (-1: constrained or not owned here).
/// Collective.
std::vector<PetscInt> global_of_local_dofs(const physics::Problem& problem);

class LocalRelaxation {
 public:
  /// Collective (the dof maps); relax() then works on rank-local data only. `max_seeds`: the
  /// most nodes a trouble spot may have (kMaxSeeds; more on a uniformly refined mesh, whose
  /// spots span 2^dim times the nodes).
  explicit LocalRelaxation(const physics::Problem& problem, int max_seeds = kMaxSeeds);

  struct Result {
    bool relaxed = false;  ///< u was changed
    int iterations = 0;    ///< local Newton steps taken
    int dofs = 0;          ///< dofs of the patch
    double before = 0;     ///< |R| on the patch's dofs before
    double after = 0;      ///< and after
  };
  /// `r` = R(u, s) (global). Where more than half of |R|^2 sits on at most max_seeds nodes (those
  /// with |R_node| >= a tenth of the largest), relaxes u on the patch of cells within three rings
  /// of them in 2D, two in 3D (the dofs whose cells all lie in the patch; not those where `fixed`, a global vector, is
  /// non-zero: the control node), until the patch's residual is a tenth of the rest's or a
  /// hundredth of its start. u stays admissible; `r` is stale where relaxed.
  Result relax(Vec u, double s, Vec r, Vec fixed);

  static constexpr int kMaxSeeds = 32;

 private:
  /// The cells and free dofs of the patch around `seeds` (nodes: first local dof / dim) into cells_, free_.
  void patch(const std::vector<PetscInt>& seeds, const PetscScalar* fixed);
  /// R on free_ at u (the patch's cells only) into rf; false where u is inadmissible.
  bool patch_residual(Vec u, double s, Eigen::VectorXd& rf);
  /// The energy at u with the patch's cells only (the rest is constant); false if inadmissible.
  bool patch_energy(Vec u, double s, double& e);
  /// The trouble spot of r = R(u): the nodes with |R_node|^2 >= a hundredth of the largest, into
  /// `seeds`; `total` = |r|^2. False where there is none to relax (r = 0, more than max_seeds_
  /// nodes, or they hold less than half of |r|^2).
  bool seed_nodes(Vec r, std::vector<PetscInt>& seeds, double& total) const;
  struct PatchFactor;
  /// The lower triangle of the patch's tangent at u on free_ into f.K (its pattern the same at
  /// every call for one patch); `diagonal` = the sum of |K_ii|. False where u is inadmissible.
  bool patch_tangent(Vec u, double s, PatchFactor& f, double& diagonal);
  /// The energy line search along d (slope = R . d < 0) from the patch energy e0 at u: halved from
  /// the whole step until Armijo's condition holds (down to 1e-6); u and e0 take the accepted
  /// trial's. False (u unchanged) where none did.
  bool descend(Vec u, double s, const Eigen::VectorXd& d, double slope, double& e0);

  const physics::Problem& problem_;
  int dim_;
  int max_seeds_;
  std::vector<PetscInt> gol_;                     ///< global_of_local_dofs
  std::vector<PetscInt> node_cells_ptr_, node_cells_;  ///< cells of each node (CSR by node)
  std::vector<PetscInt> cells_;                   ///< the patch's cells, sorted
  std::vector<PetscInt> free_;                    ///< the patch's free dofs (global indices)
  std::vector<char> in_patch_;                    ///< per local cell
  std::vector<int> position_;                     ///< global dof -> index in free_ (-1)
  core::VecH work_, trial_;
  core::MatH K_;                                  ///< the patch's tangent (the full pattern)
};

}  // namespace hypershape::solver
