#pragma once
/// Algebraic multigrid for the tangent: the linear solver of large 3D meshes, where a sparse
/// factorisation grows like N^2 (FACTS.md: 0.3 s at 7.8k, 20 s at 55k unknowns of 3D P2).
///
///  - gamg:  CG preconditioned by PETSc's smoothed-aggregation AMG, with the six rigid-body
///           modes of the displacement space as its near-null space (MatNullSpaceCreateRigidBody
///           on the nodal coordinates, laid out like the solution: clamped nodes removed, P2
///           edge nodes included), interpolation reused between the tangents of one problem.
///  - hypre: CG preconditioned by hypre's BoomerAMG (systems AMG, unknown approach: one
///           function per displacement component), strong threshold 0.5 (FACTS.md: halved its
///           cost at nu = 0.49). Nodal coarsening (-amg_pc_hypre_boomeramg_nodal_coarsen 6, and
///           the rigid-body modes with -amg_pc_hypre_boomeramg_vec_interp_variant 3) is an option:
///           measured 3.6-4x more preconditioner applications on the ball (multigrid.cpp).
/// Every default is set only where the options database does not give one (prefix
/// `<prefix>amg_`: -amg_ksp_type gmres, -amg_pc_gamg_threshold 0.02, ...).
///
/// An AMG preconditioner gives no inertia: the stability check of a converged state (the
/// tangent positive definite) is made by smallest_eigenvalue() instead (LOBPCG preconditioned
/// by the same AMG), see Tangent::stability().
#include <petscksp.h>

#include <cstdint>
#include <optional>
#include <string>

#include "hypershape/core/petsc_handle.hpp"
#include "hypershape/physics/problem.hpp"

namespace hypershape::solver {

/// The linear solver of the tangent (config key `solver: {linear: ...}`).
enum class LinearSolver {
  automatic,  ///< by size: gamg in 3D from TangentOptions::auto_dofs unknowns, else direct
  direct,     ///< LDL^T factorisation (PETSc's blocked one in 2D on one rank, MUMPS otherwise)
  gamg,       ///< CG + PETSc GAMG with the rigid-body near-null space
  hypre,      ///< CG + hypre BoomerAMG with nodal coarsening
};

/// "auto", "direct", "gamg", "hypre".
const char* to_string(LinearSolver s);
/// The value of a name to_string() gives; nothing for any other text.
std::optional<LinearSolver> linear_solver_from_string(const std::string& name);
/// `automatic` decided: gamg for a 3D problem of at least `auto_dofs` unknowns, direct
/// otherwise; any other choice is returned as it is.
LinearSolver resolve_linear_solver(LinearSolver requested, int dim, std::int64_t n_dofs_global,
                                   std::int64_t auto_dofs);

/// Attaches the rigid-body modes of the problem's displacement space to A as its near-null
/// space (and A's block size must be dim). Collective.
void set_rigid_body_near_null_space(const physics::Problem& problem, Mat A);

/// A KSP (CG) preconditioned by `kind` (gamg or hypre) on `comm`, options prefix `prefix`
/// (+ "amg_"), configured from the options database. Operators are set by the caller. Collective.
core::KSPH make_multigrid_ksp(MPI_Comm comm, LinearSolver kind, const std::string& prefix);

/// The smallest eigenvalue of a symmetric A by LOBPCG (block size 1) preconditioned by `pc`,
/// from `x` (overwritten with the Ritz vector). Stops when the sign is settled: the Rayleigh
/// quotient (an upper bound of the smallest eigenvalue) is negative (certain), or the residual
/// of a positive one is below `rtol` times it, or it fell by less than 1% over 10 iterations
/// (not a proof: a negative eigenvalue whose mode the iteration has not yet found would be
/// missed; from a pseudo-random start the lowest mode is the one LOBPCG finds first). Collective.
struct EigenEstimate {
  double value = 0;         ///< the last Rayleigh quotient
  double residual = 0;      ///< ||A x - value x|| / ||x||
  int iterations = 0;
  bool settled = false;     ///< value < 0 (certain), or value > 0 converged or stalled
};
EigenEstimate smallest_eigenvalue(Mat A, PC pc, Vec x, double rtol, int max_iterations);

}  // namespace hypershape::solver
