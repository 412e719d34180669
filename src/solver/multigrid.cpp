#include "hypershape/solver/multigrid.hpp"

#include <petscmat.h>

#include <Eigen/Dense>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "hypershape/core/error.hpp"
#include "hypershape/core/vec_array.hpp"

namespace hypershape::solver {

const char* to_string(LinearSolver s) {
  switch (s) {
    case LinearSolver::automatic: return "auto";
    case LinearSolver::direct: return "direct";
    case LinearSolver::gamg: return "gamg";
    case LinearSolver::hypre: return "hypre";
  }
  return "?";
}

std::optional<LinearSolver> linear_solver_from_string(const std::string& name) {
  for (auto s : {LinearSolver::automatic, LinearSolver::direct, LinearSolver::gamg, LinearSolver::hypre})
    if (name == to_string(s)) return s;
  return std::nullopt;
}

LinearSolver resolve_linear_solver(LinearSolver requested, int dim, std::int64_t n_dofs_global,
                                   std::int64_t auto_dofs) {
  if (requested != LinearSolver::automatic) return requested;
  return dim == 3 && n_dofs_global >= auto_dofs ? LinearSolver::gamg : LinearSolver::direct;
}

void set_rigid_body_near_null_space(const physics::Problem& problem, Mat A) {
  const int dim = problem.space().dim();
  DM dm = problem.dm();
  core::VecH g = problem.create_vector();
  Vec xl;
  HS_PETSC(DMGetLocalVector(dm, &xl));
  HS_PETSC(VecSet(xl, 0.0));
  {
    core::VecArray<PetscScalar> a(xl);
    for (const auto& n : problem.space().owned_nodes())
      for (int i = 0; i < dim; ++i) a[n.offset + i] = n.x[std::size_t(i)];
  }
  HS_PETSC(DMLocalToGlobal(dm, xl, INSERT_VALUES, g));  // clamped nodes drop out, as in u
  HS_PETSC(DMRestoreLocalVector(dm, &xl));
  PetscInt n, N, bs;
  HS_PETSC(VecGetLocalSize(g, &n));
  HS_PETSC(VecGetSize(g, &N));
  HS_PETSC(MatGetBlockSize(A, &bs));
  if (n % dim != 0 || bs != dim)
    throw std::logic_error("rigid-body modes: the displacement layout is not in blocks of dim");
  core::VecH coords;  // the same values with block size dim (MatNullSpaceCreateRigidBody reads it)
  HS_PETSC(VecCreate(problem.comm(), coords.out()));
  HS_PETSC(VecSetSizes(coords, n, N));
  HS_PETSC(VecSetBlockSize(coords, dim));
  HS_PETSC(VecSetType(coords, VECSTANDARD));
  {
    core::VecArray<const PetscScalar> src(g.get());
    core::VecArray<PetscScalar> dst(coords.get());
    for (PetscInt i = 0; i < n; ++i) dst[i] = src[i];
  }
  MatNullSpace modes;
  HS_PETSC(MatNullSpaceCreateRigidBody(coords, &modes));
  HS_PETSC(MatSetNearNullSpace(A, modes));
  HS_PETSC(MatNullSpaceDestroy(&modes));
}

namespace {

/// Sets `-<prefix><name> value` unless the options database already has it.
void default_option(const std::string& prefix, const std::string& name, const char* value) {
  PetscBool set = PETSC_FALSE;
  HS_PETSC(PetscOptionsHasName(nullptr, prefix.c_str(), ("-" + name).c_str(), &set));
  if (!set) HS_PETSC(PetscOptionsSetValue(nullptr, ("-" + prefix + name).c_str(), value));
}

}  // namespace

core::KSPH make_multigrid_ksp(MPI_Comm comm, LinearSolver kind, const std::string& prefix) {
  const std::string p = prefix + "amg_";
  core::KSPH ksp;
  HS_PETSC(KSPCreate(comm, ksp.out()));
  HS_PETSC(KSPSetOptionsPrefix(ksp, p.c_str()));
  HS_PETSC(KSPSetType(ksp, KSPCG));
  // The forcing term is relative to ||b|| of the true residual (as the kept-factor GMRES).
  HS_PETSC(KSPSetNormType(ksp, KSP_NORM_UNPRECONDITIONED));
  PC pc;
  HS_PETSC(KSPGetPC(ksp, &pc));
  if (kind == LinearSolver::gamg) {
    HS_PETSC(PCSetType(pc, PCGAMG));
    // Aggregates and prolongators of the first tangent kept for the later ones of the problem
    // (the pattern never changes; the values are re-smoothed, the Galerkin products redone).
    HS_PETSC(PCGAMGSetReuseInterpolation(pc, PETSC_TRUE));
  } else if (kind == LinearSolver::hypre) {
    HS_PETSC(PCSetType(pc, PCHYPRE));
    HS_PETSC(PCHYPRESetType(pc, "boomeramg"));
    // The unknown approach (one function per displacement component, from the block size):
    // on the ball (P2 h 0.3, 15k unknowns, one load case) nodal coarsening
    // (-amg_pc_hypre_boomeramg_nodal_coarsen 6) took 1642 preconditioner applications against
    // 386 without, and with the rigid-body modes (vec_interp_variant 3) 1385, each 4x dearer.
    default_option(p, "pc_hypre_boomeramg_strong_threshold", "0.5");
  } else {
    throw std::logic_error("make_multigrid_ksp: not a multigrid kind");
  }
  HS_PETSC(KSPSetFromOptions(ksp));
  return ksp;
}

namespace {

using Small = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 3, 3>;

/// The lowest eigenpair of the pencil (G, B) restricted to the first n basis vectors; false if
/// B is not numerically positive definite there (the basis has become dependent).
bool lowest_ritz_pair(const Small& G, const Small& B, int n, double& value, Eigen::VectorXd& c) {
  const Small Bn = B.topLeftCorner(n, n), Gn = G.topLeftCorner(n, n);
  Eigen::SelfAdjointEigenSolver<Small> b(Bn);
  if (b.info() != Eigen::Success || !(b.eigenvalues()(0) > 1e-10 * b.eigenvalues()(n - 1))) return false;
  Eigen::GeneralizedSelfAdjointEigenSolver<Small> s(Gn, Bn);
  if (s.info() != Eigen::Success) return false;
  value = s.eigenvalues()(0);
  c = s.eigenvectors().col(0);
  return std::isfinite(value);
}

}  // namespace

namespace {

/// Block-size-1 LOBPCG's state: the iterate x, the preconditioned residual w, the previous
/// direction p, and their products with A.
struct Lobpcg {
  Mat A;
  Vec x;
  core::VecH Ax, r, w, Aw, p, Ap, t, At;
  bool have_p = false;

  Lobpcg(Mat A_, Vec x_) : A(A_), x(x_) {
    for (core::VecH* v : {&Ax, &r, &w, &Aw, &p, &Ap, &t, &At}) HS_PETSC(VecDuplicate(x, v->out()));
  }

  /// Normalises x; its Rayleigh quotient.
  double start() {
    PetscReal nrm, lam;
    HS_PETSC(VecNormalize(x, &nrm));
    HS_PETSC(MatMult(A, x, Ax));
    HS_PETSC(VecDot(x, Ax, &lam));
    return lam;
  }

  /// One step: w = pc(r), Rayleigh-Ritz on span{x, w, p}; the new quotient, or false if the
  /// step broke down.
  bool step(PC pc, double& lam) {
    PetscReal nrm;
    HS_PETSC(PCApply(pc, r, w));
    HS_PETSC(VecNormalize(w, &nrm));
    if (!(nrm > 0) || !std::isfinite(nrm)) return false;
    HS_PETSC(MatMult(A, w, Aw));
    Vec S[3] = {x, w, p}, AS[3] = {Ax, Aw, Ap};
    Small G(3, 3), B(3, 3);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j <= i; ++j) {
        PetscReal g, b;
        HS_PETSC(VecDot(S[i], AS[j], &g));
        HS_PETSC(VecDot(S[i], S[j], &b));
        G(i, j) = G(j, i) = g, B(i, j) = B(j, i) = b;
      }
    double value;
    Eigen::VectorXd c;
    int n = have_p ? 3 : 2;
    if (!lowest_ritz_pair(G, B, n, value, c)) {
      if (n == 2 || !lowest_ritz_pair(G, B, n = 2, value, c)) return false;
    }
    // p <- c1 w + c2 p, x <- c0 x + p (and their products with A alike).
    const double c2 = n == 3 ? c(2) : 0.0;
    HS_PETSC(VecAXPBYPCZ(t, c(1), c2, 0.0, w, p));
    HS_PETSC(VecAXPBYPCZ(At, c(1), c2, 0.0, Aw, Ap));
    HS_PETSC(VecAXPBY(x, 1.0, c(0), t));
    HS_PETSC(VecAXPBY(Ax, 1.0, c(0), At));
    HS_PETSC(VecNorm(t, NORM_2, &nrm));
    have_p = nrm > 0;
    if (have_p) {
      HS_PETSC(VecAXPBY(p, 1.0 / nrm, 0.0, t));
      HS_PETSC(VecAXPBY(Ap, 1.0 / nrm, 0.0, At));
    }
    HS_PETSC(VecNorm(x, NORM_2, &nrm));
    HS_PETSC(VecScale(x, 1.0 / nrm));
    HS_PETSC(VecScale(Ax, 1.0 / nrm));
    PetscReal q;
    HS_PETSC(VecDot(x, Ax, &q));
    lam = q;
    return true;
  }
};

}  // namespace

EigenEstimate smallest_eigenvalue(Mat A, PC pc, Vec x, double rtol, int max_iterations) {
  Lobpcg it(A, x);
  double lam = it.start();
  EigenEstimate e;
  std::vector<double> history;
  for (int k = 0;; ++k) {
    HS_PETSC(VecWAXPY(it.r, -lam, x, it.Ax));
    PetscReal rn;
    HS_PETSC(VecNorm(it.r, NORM_2, &rn));
    e.value = lam, e.residual = rn, e.iterations = k;
    if (!std::isfinite(lam) || !std::isfinite(rn)) return e;
    // The sign is settled by a negative Rayleigh quotient (an upper bound of the smallest
    // eigenvalue), by a small residual, or by a quotient that has stopped falling: 1% over 10
    // iterations (the residual of a near-double eigenvalue, e.g. the ball's two bending modes,
    // converges far more slowly than the quotient: measured 70 against 40 iterations).
    history.push_back(lam);
    const bool stalled = k >= 10 && history[std::size_t(k - 10)] - lam <= 0.01 * lam;
    if (lam < 0 || rn <= rtol * lam || stalled) {
      e.settled = true;
      return e;
    }
    if (k == max_iterations || !it.step(pc, lam)) return e;
  }
}

}  // namespace hypershape::solver
