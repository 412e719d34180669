#pragma once
/// One LDL^T factorisation of a symmetric tangent, kept for solves and for its inertia.
///
/// Two kinds, chosen once per problem:
///  - blocked (2D, one rank, block size 2): the tangent's values are scattered into a symmetric
///    block matrix (SBAIJ, 2x2 blocks, one per node) in a fill-reducing ordering of the nodes
///    (approximate minimum degree on the node graph, computed once), and factored U^T D U by
///    BlockLdlt2 (block_ldlt.hpp: PETSc's blocked kernel's arithmetic, vectorised, the same bits).
///    Measured on the disk (P1 h 0.04, 4.7k unknowns), PETSc's blocked kernel against its scalar one:
///    numeric factorisation 2.3-3.6x faster and triangular solves 2.3x faster than the scalar
///    factorisation of the AIJ matrix in the qmd ordering, with as many nonzeros in the factor.
///    PETSc 3.18 has no MatGetInertia for 2x2 blocks: the inertia is counted from the 2x2
///    diagonal blocks of D (stored inverted; a block and its inverse have the same inertia), by
///    Sylvester's law, tested against dense eigenvalues and MUMPS.
///  - general (3D, solver groups, or another factorisation asked for in the options): a copy of
///    the matrix factored by a preonly Cholesky KSP (configure_direct_solver; the KSP's options
///    prefix applies), inertia from MUMPS's INFOG(12) or MatGetInertia.
///  - single (asked for with `single`, symmetric, one rank): MUMPS's single-precision factor,
///    solves refined to double precision (single_factor.hpp); inertia from its pivots.
///  - LU (symmetric = false: a tangent with a follower load's stiffness): a copy of the matrix
///    factored by a preonly LU KSP, PETSc's own LU in 2D on one rank, MUMPS otherwise. No inertia
///    (an LU factor has none): negative_eigenvalues() is -1.
#include <petscksp.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "hypershape/core/petsc_handle.hpp"
#include "hypershape/physics/problem.hpp"
#include "hypershape/solver/block_ldlt.hpp"
#include "hypershape/solver/single_factor.hpp"

namespace hypershape::solver {

/// The number of negative eigenvalues of the matrix a Cholesky (LDL^T) KSP has factored, by
/// Sylvester's law of inertia: the negative pivots of MUMPS (INFOG(12)) or of PETSc's own
/// factorisation (MatGetInertia; 2x2 blocks: from D). -1 where the KSP holds no such factorisation.
int negative_eigenvalues(KSP ksp);

/// The blocked factor's fill-reducing node ordering of a matrix of 2x2 blocks (block size 2, one
/// rank): SuiteSparse's AMD on the block graph, the permutation PETSc's MatGetOrdering(AMD) gives
/// for the matrix converted to BAIJ, without the conversion. perm[new] = old node.
std::vector<PetscInt> amd_node_ordering(Mat A);

/// Sets a KSP to LDL^T (`symmetric`) or LU: PETSc's own (LDL^T: qmd ordering, LU: nested
/// dissection) in 2D on one rank, MUMPS otherwise (options with the KSP's prefix still apply when
/// the caller calls KSPSetFromOptions).
void configure_direct_solver(KSP ksp, MPI_Comm comm, int dim, bool symmetric = true);

/// A GMRES KSP on `comm`, right-preconditioned (its test sees the true residual) by a shell PC
/// that calls `apply(pc, x, y)` with `ctx`: a kept factor as the preconditioner. Collective.
core::KSPH make_factor_preconditioned_gmres(MPI_Comm comm, void* ctx, PetscErrorCode (*apply)(PC, Vec, Vec),
                                            const char* name);

class LdltFactor {
 public:
  /// Collective. `prefix`: options prefix of the factor's KSP. `symmetric` false: an LU factor.
  /// `single`: the mixed-precision kind where it applies (symmetric, one rank, no factorisation
  /// options given), the others otherwise.
  LdltFactor(const physics::Problem& problem, const std::string& prefix, bool symmetric = true, bool single = false);
  LdltFactor(const LdltFactor&) = delete;
  LdltFactor& operator=(const LdltFactor&) = delete;

  /// Factorises A (the problem's matrix layout); the analysis is done on the first call only.
  /// False if the factorisation failed (e.g. a zero pivot). Collective.
  bool factorise(Mat A);
  /// x = A^-1 b for the A last factorised. False if the solve failed. Collective.
  bool solve(Vec b, Vec x);
  /// x1 = A^-1 b1 and x2 = A^-1 b2, the same numbers as two solve() calls (the blocked kind reads
  /// its factor once for both). False if a solve failed. Collective.
  /// `absolute` (has_absolute()): with U^T |D| U instead, unrefined (refinement would take its
  /// solutions back to the factorised matrix's).
  bool solve_pair(Vec b1, Vec x1, Vec b2, Vec x2, bool absolute = false);
  /// x ~ A^-1 b inside a preconditioner: the single kind's unrefined solve, the others' solve.
  bool precondition(Vec b, Vec x) { return single_ ? single_->solve_unrefined(b, x) : solve(b, x); }
  /// Negative eigenvalues of the A last factorised; -1 unknown. Collective.
  int negative_eigenvalues() const;
  bool factored() const { return factored_; }
  /// Whether solve_pair(..., absolute = true) solves with U^T |D| U (the 2D blocked factor).
  bool has_absolute() const { return blocked_ && !single_; }
  bool blocked() const { return blocked_; }
  bool single() const { return single_ != nullptr; }

 private:
  void set_up_blocked(Mat A);
  /// The new block index of each node (old block), and old_of_new_ (scalar).
  std::vector<PetscInt> node_ordering(Mat A);
  /// F_ with the upper 2x2-block pattern of A in the new ordering, and source_ / target_.
  void build_block_pattern(Mat A, const std::vector<PetscInt>& new_block);
  void scatter_values(Mat A);
  /// Blocked kind: GMRES on F_ preconditioned by the factor where the solve y of F_ y = b (both
  /// in the new ordering) lost digits.
  void refine(Vec b, Vec y);
  /// Blocked kind: b (old ordering) into bp (new), and yp (new) into x (old).
  void to_new(Vec b, Vec bp) const;
  void to_old(Vec yp, Vec x) const;
  /// Blocked kind: y = F_^-1 x with block_.
  void block_solve(Vec x, Vec y) const;
  static PetscErrorCode apply_factor(PC pc, Vec x, Vec y);

  bool symmetric_ = true;
  bool blocked_ = false;
  BlockLdlt2 block_;  ///< the blocked kind's factor (of F_'s values)
  bool factored_ = false;
  bool analysed_ = false;
  core::MatH F_;    ///< the matrix factored: a copy of A (general) or its blocked permutation
  core::KSPH ksp_;
  // Blocked kind: old scalar index of new scalar index i = 2 node[i / 2] + i % 2 ...
  std::vector<PetscInt> old_of_new_;
  /// ... and where F_'s values come from: value source_[k] of A's CSR values goes to position
  /// target_[k] of F_'s (the upper triangle's only; in F_'s order, so the writes stream).
  std::vector<std::uint32_t> source_, target_;
  core::VecH xp_, yp_, rp_;  ///< b, x and the residual in the new ordering
  core::VecH xp2_, yp2_;     ///< solve_pair's second b and x in the new ordering
  AlignedDoubles pair_;  ///< solve_pair's right-hand sides, interleaved by node (on cache lines)
  core::KSPH refine_;
  std::unique_ptr<SingleFactor> single_;  ///< the single kind (then F_ and ksp_ are unused)
};

}  // namespace hypershape::solver
