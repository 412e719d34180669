#pragma once
/// A 2D P2 load case that the path, its branch switches and the retry from rest lost, started
/// once more from the P1 solution on the same mesh (SolverOptions::p1_start, issue 23).
///
/// P1 at nu 0.49 locks, and locking is stiffness: on the shapes where P2 loses a load case next to
/// the clamp, P1 on the same mesh mostly converges (docs/STABILITY.md, "Which discretisation loses
/// these load cases"). Its state at the target, prolonged to P2 (vertex values copied, edge
/// midpoints the mean of their edge's ends: the same field), is a start from which the P2 path and
/// its branch switches look for a stable equilibrium on target in another basin than the path from
/// rest. A converged load case is checked as every other (true residual, positive definite
/// tangent, max|u| on target); only load cases that had failed change. Measured on five seeds
/// of the Random2D preset (docs/SOLVER.md, "from the P1 solution"): 5 of the 16 failures that
/// were not verified folds reached a verified stable state on target this way.
#include <mpi.h>

#include <memory>
#include <optional>

#include "hypershape/config/dataset.hpp"
#include "hypershape/core/petsc_handle.hpp"
#include "hypershape/factory/dataset_scene.hpp"
#include "hypershape/solver/nonlinear.hpp"

namespace hypershape::factory {

/// The P1 problem of a shape, built at its first use (most shapes never need it).
class P1Start {
 public:
  /// For the P2 problem of `cfg` on `shape`; nothing is built yet. The references must outlive it.
  P1Start(MPI_Comm group, const config::DatasetConfig& cfg, const ShapeSample& shape)
      : group_(group), cfg_(cfg), shape_(shape) {}
  /// Whether a load case that failed so (its reason) is tried from P1.
  bool applies(const solver::TargetResult& failed) const;
  /// Solves `lc` with P1 and, where that converged, `p2`'s target from its state prolonged
  /// (`p2`'s problem set to `lc`). The outcome: P2's, with the failed try's and the P1 solve's
  /// iterations added as recovery; nothing where P1 did not converge (then `failed` stands, its
  /// reason extended in `note`). Collective over the group.
  std::optional<solver::TargetResult> solve(const LoadCase& lc, solver::NonlinearSolver& p2,
                                            const solver::TargetResult& failed, std::string& note);

 private:
  MPI_Comm group_;
  const config::DatasetConfig& cfg_;
  const ShapeSample& shape_;
  ShapeProblem sp_;
  std::unique_ptr<solver::NonlinearSolver> nl_;
};

/// u1, a P1 field of `p1`, as a P2 field of `p2` on the same mesh (the same function). Collective.
core::VecH prolong_p1_to_p2(const physics::Problem& p1, Vec u1, const physics::Problem& p2);

}  // namespace hypershape::factory
