#pragma once
/// A mixed-precision LDL^T of a symmetric matrix on one rank: MUMPS's single-precision
/// factorisation (SMUMPS, sym = 2: symmetric indefinite, 2x2 pivots) with every solve refined to
/// double precision against the matrix itself.
///
/// Why: in 3D the numeric factorisation is most of a load case (64% of the Random3D preset's
/// phases) and MUMPS spends it in dense kernels of the fronts, where single precision moves half
/// the bytes and runs twice the flops. Measured on a 3D P2 tangent of 18k unknowns (the ball at
/// the preset's mesh, OpenBLAS, one core): factorisation 0.20 s in single against 0.31 s in
/// double, the same ordering and fill; two to three refinement steps bring the residual from
/// 5e-7 to 1e-14.
///
/// Solve: x = 0, r = b; repeat x += F^-1 r (in single), r = b - A x (in double) until |r| <=
/// 1e-10 |b| (the blocked LDL^T's test, ldlt.cpp), at most 10 times; where it stagnates (an
/// indefinite matrix near singular) GMRES on A right-preconditioned by F goes on from x. The
/// inertia is the factor's negative pivots (INFOG(12)), as with MUMPS in double.
#include <petscmat.h>

#include <memory>
#include <vector>

#include "hypershape/core/petsc_handle.hpp"

namespace hypershape::solver {

class SingleFactor {
 public:
  SingleFactor();
  ~SingleFactor();
  SingleFactor(const SingleFactor&) = delete;
  SingleFactor& operator=(const SingleFactor&) = delete;

  /// Factorises A (MATSEQAIJ; the pattern of the first call is kept: analysis once). False if the
  /// factorisation failed (singular, or out of memory after two enlargements).
  bool factorise(Mat A);
  /// x = A^-1 b to a relative residual of 1e-10 (or the best GMRES found in 30 iterations: the
  /// Newton iteration judges). False on a non-finite result or without a factor.
  bool solve(Vec b, Vec x);
  /// x = F^-1 b: one single-precision solve, not refined (relative error ~1e-7 times the
  /// condition number), for use inside a preconditioner. False on a non-finite result or without
  /// a factor.
  bool solve_unrefined(Vec b, Vec x);
  /// Negative eigenvalues of the A last factorised (negative pivots); -1 without a factor.
  int negative_eigenvalues() const { return factored_ ? negative_ : -1; }
  bool factored() const { return factored_; }
  /// Refinement steps (single-precision solves) of the last solve, GMRES iterations included.
  int last_refinement_steps() const { return steps_; }

 private:
  void analyse(Mat A);
  void solve_single(Vec r, Vec d);  ///< d = F^-1 r, through the single-precision factor
  static PetscErrorCode apply(PC pc, Vec x, Vec y);

  struct Mumps;
  std::unique_ptr<Mumps> m_;
  std::vector<PetscInt> upper_;  ///< CSR positions of A's upper-triangle entries, in MUMPS's order
  std::vector<float> values_, rhs_;
  core::MatH A_;                 ///< the matrix factorised (the refinement's residual is against it)
  core::VecH r_, d_;
  core::KSPH gmres_;             ///< the fallback where the refinement stagnates
  bool analysed_ = false, factored_ = false;
  int negative_ = -1, steps_ = 0;
};

}  // namespace hypershape::solver
