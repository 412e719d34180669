#pragma once
/// Shared helpers for the verification tests: nodal interpolation of analytic fields, local
/// vectors with the (homogeneous) essential values, quadrature L2 errors, facet predicates and
/// the seed paper's disk scene.
#include <petscdmplex.h>
// after a PETSc header: petscblaslapack.h uses PETSC_COMM_SELF without including petscsys.h
#include <petscblaslapack.h>

#include <cmath>
#include <cstring>
#include <functional>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "hypershape/core/error.hpp"
#include "hypershape/core/petsc_handle.hpp"
#include "hypershape/mesh/gmsh_mesher.hpp"
#include "hypershape/physics/problem.hpp"
#include "hypershape/physics/registry.hpp"
#include "hypershape/solver/nonlinear.hpp"

namespace hstest {

namespace hs = hypershape;
using Field = std::function<void(const double* x, double* u)>;

/// A PETSc option set for a scope (cleared at its end, also when a REQUIRE leaves it).
struct ScopedOption {
  std::string name;
  ScopedOption(std::string n, const char* value = nullptr) : name(std::move(n)) {
    HS_PETSC(PetscOptionsSetValue(nullptr, name.c_str(), value));
  }
  ~ScopedOption() { PetscOptionsClearValue(nullptr, name.c_str()); }
  ScopedOption(const ScopedOption&) = delete;
  ScopedOption& operator=(const ScopedOption&) = delete;
};

/// A local vector of the problem's DM holding the global vector `u`, with the homogeneous
/// essential values (zero) in the constrained slots. Collective.
/// Entries of this rank's part of a global vector.
inline std::vector<double> values(Vec v) {
  PetscInt n;
  HS_PETSC(VecGetLocalSize(v, &n));
  const PetscScalar* a;
  HS_PETSC(VecGetArrayRead(v, &a));
  std::vector<double> out(a, a + n);
  HS_PETSC(VecRestoreArrayRead(v, &a));
  return out;
}

inline bool bitwise_equal(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}

/// Rank 0's value on every rank of PETSC_COMM_WORLD. Collective.
inline double broadcast(double v) {
  MPI_Bcast(&v, 1, MPI_DOUBLE, 0, PETSC_COMM_WORLD);
  return v;
}

/// The same mesh: dimension, cells and coordinates bit for bit.
inline bool same_mesh(const hs::mesh::MeshData& a, const hs::mesh::MeshData& b) {
  return a.dim == b.dim && a.cells == b.cells && a.coords == b.coords;
}

inline bool all_finite(const std::vector<double>& a) {
  for (double v : a)
    if (!std::isfinite(v)) return false;
  return true;
}

inline hs::core::VecH local_copy(const hs::physics::Problem& p, Vec u) {
  hs::core::VecH ul;
  HS_PETSC(DMCreateLocalVector(p.dm(), ul.out()));
  HS_PETSC(VecZeroEntries(ul));
  HS_PETSC(DMGlobalToLocal(p.dm(), u, INSERT_VALUES, ul));
  return ul;
}

/// Sets the global vector `u` to the nodal interpolant of `f` (constrained dofs are dropped by
/// the global layout). Collective.
inline void interpolate(const hs::physics::Problem& p, const Field& f, Vec u) {
  const int dim = p.space().dim();
  hs::core::VecH ul;
  HS_PETSC(DMCreateLocalVector(p.dm(), ul.out()));
  HS_PETSC(VecZeroEntries(ul));
  PetscScalar* a;
  HS_PETSC(VecGetArray(ul, &a));
  for (const auto& n : p.space().owned_nodes()) {
    double v[3] = {0, 0, 0};
    f(n.x.data(), v);
    for (int i = 0; i < dim; ++i) a[n.offset + i] = v[i];
  }
  HS_PETSC(VecRestoreArray(ul, &a));
  HS_PETSC(VecZeroEntries(u));
  HS_PETSC(DMLocalToGlobal(p.dm(), ul, INSERT_VALUES, u));
}

/// ( int_Omega |u_h - u*|^2 )^(1/2) with the space's cell rule (all quadrature points). Collective.
inline double l2_error(const hs::physics::Problem& p, Vec u, const Field& exact) {
  const auto& s = p.space();
  const int dim = s.dim(), nb = s.n_nodes();
  hs::core::VecH ul = local_copy(p, u);
  const PetscScalar* a;
  HS_PETSC(VecGetArrayRead(ul, &a));
  double sum = 0;
  for (PetscInt c = s.cell_begin(); c < s.cell_end(); ++c) {
    const PetscInt* idx = s.local_dofs(c);
    for (int q = 0; q < s.n_qp(); ++q) {
      double x[3] = {0, 0, 0}, ue[3] = {0, 0, 0}, uh[3] = {0, 0, 0};
      s.map_point(c, q, x);
      exact(x, ue);
      for (int b = 0; b < nb; ++b)
        for (int i = 0; i < dim; ++i) uh[i] += s.basis(q, b) * PetscRealPart(a[idx[b * dim + i]]);
      double e2 = 0;
      for (int i = 0; i < dim; ++i) e2 += (uh[i] - ue[i]) * (uh[i] - ue[i]);
      sum += s.qweight(q) * s.det_jacobian(c) * e2;
    }
  }
  HS_PETSC(VecRestoreArrayRead(ul, &a));
  MPI_Allreduce(MPI_IN_PLACE, &sum, 1, MPI_DOUBLE, MPI_SUM, p.comm());
  return std::sqrt(sum);
}

/// Measure of the domain by the cell rule (a check of weights, det J and the partition).
inline double domain_measure(const hs::physics::Problem& p) {
  const auto& s = p.space();
  double sum = 0;
  for (PetscInt c = s.cell_begin(); c < s.cell_end(); ++c)
    for (int q = 0; q < s.n_qp(); ++q) sum += s.qweight(q) * s.det_jacobian(c);
  MPI_Allreduce(MPI_IN_PLACE, &sum, 1, MPI_DOUBLE, MPI_SUM, p.comm());
  return sum;
}

/// Facets whose vertices all have coordinate `axis` equal to `value` (to 1e-12).
inline hs::physics::FacetPredicate on_plane(int axis, double value) {
  return [axis, value](const double* x, int nv, int dim) {
    for (int a = 0; a < nv; ++a)
      if (std::abs(x[a * dim + axis] - value) > 1e-12) return false;
    return true;
  };
}

inline hs::physics::FacetPredicate everywhere() {
  return [](const double*, int, int) { return true; };
}

/// || a - b ||_2 / || b ||_2 of two global vectors (collective).
inline double rel_diff(Vec a, Vec b) {
  hs::core::VecH d;
  HS_PETSC(VecDuplicate(a, d.out()));
  HS_PETSC(VecWAXPY(d, -1.0, b, a));
  PetscReal nd, nb;
  HS_PETSC(VecNorm(d, NORM_2, &nd));
  HS_PETSC(VecNorm(b, NORM_2, &nb));
  return nd / nb;
}

/// The seed paper's 2D scene: unit disk clamped near (1, 0) (r = 0.5), Gaussian traction at
/// (-1, 0) pointing in +y (gamma 0.2), Neo-Hookean E = 500, nu = 0.49.
inline hs::mesh::MeshData disk_mesh(double h) {
  hs::mesh::MeshOptions mo;
  mo.h = h;
  return hs::mesh::mesh_disk(mo, hs::mesh::ClampRegion{{1.0, 0.0, 0.0}, 0.5});
}

inline std::vector<hs::physics::EffectPtr> disk_effects(double E = 500, double nu = 0.49) {
  std::vector<hs::physics::EffectPtr> e;
  e.push_back(hs::physics::make_neo_hookean(E, nu));
  e.push_back(hs::physics::make_dirichlet_patch({1.0, 0.0}, 0.5));
  e.push_back(hs::physics::make_gaussian_traction({-1.0, 0.0}, {0.0, 1.0}, 0.2));
  return e;
}

/// The unit ball with its boundary meshed to a Dirichlet patch near (1, 0, 0) (r = 0.5), the 3D
/// analogue of disk_mesh.
inline hs::mesh::MeshData ball_mesh(double h) {
  hs::mesh::MeshOptions mo;
  mo.h = h;
  return hs::mesh::mesh_ball(mo, hs::mesh::ClampRegion{{1.0, 0.0, 0.0}, 0.5});
}

/// The seed paper's 3D scene on ball_mesh: Neo-Hookean E = 500, nu = 0.49, clamped near (1, 0, 0)
/// (r = 0.5), Gaussian traction at (-1, 0, 0) pointing in +y (gamma 0.2).
inline std::vector<hs::physics::EffectPtr> ball_effects() {
  std::vector<hs::physics::EffectPtr> e;
  e.push_back(hs::physics::make_neo_hookean(500.0, 0.49));
  e.push_back(hs::physics::make_dirichlet_patch({1.0, 0.0, 0.0}, 0.5));
  e.push_back(hs::physics::make_gaussian_traction({-1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, 0.2));
  return e;
}

/// The mean of A's diagonal (a scale for shifts that make a tangent indefinite). Collective.
inline double mean_diagonal(Mat A) {
  hs::core::VecH d;
  HS_PETSC(MatCreateVecs(A, d.out(), nullptr));
  HS_PETSC(MatGetDiagonal(A, d));
  PetscReal sum;
  PetscInt n;
  HS_PETSC(VecSum(d, &sum));
  HS_PETSC(VecGetSize(d, &n));
  return sum / double(n);
}

/// Negative eigenvalues of the symmetric matrix A by a fresh LDL^T of `package` (MUMPS, PETSc).
inline int ldlt_negative_eigenvalues(Mat A, const char* package) {
  KSP ksp;
  PC pc;
  MPI_Comm comm;
  HS_PETSC(PetscObjectGetComm(reinterpret_cast<PetscObject>(A), &comm));
  HS_PETSC(KSPCreate(comm, &ksp));
  HS_PETSC(KSPSetType(ksp, KSPPREONLY));
  HS_PETSC(KSPGetPC(ksp, &pc));
  HS_PETSC(PCSetType(pc, PCCHOLESKY));
  HS_PETSC(PCFactorSetMatSolverType(pc, package));
  HS_PETSC(KSPSetOperators(ksp, A, A));
  HS_PETSC(KSPSetUp(ksp));
  const int neg = hs::solver::negative_eigenvalues(ksp);
  HS_PETSC(KSPDestroy(&ksp));
  return neg;
}

/// || K - K^T ||_F / || K ||_F (collective).
inline double asymmetry(Mat K) {
  Mat Kt;
  HS_PETSC(MatTranspose(K, MAT_INITIAL_MATRIX, &Kt));
  HS_PETSC(MatAXPY(Kt, -1.0, K, DIFFERENT_NONZERO_PATTERN));
  PetscReal d, k;
  HS_PETSC(MatNorm(Kt, NORM_FROBENIUS, &d));
  HS_PETSC(MatNorm(K, NORM_FROBENIUS, &k));
  HS_PETSC(MatDestroy(&Kt));
  return d / k;
}

/// How often PETSc's own log saw `event` (logging must be on: PetscLogDefaultBegin); -1 unknown.
inline PetscLogDouble event_count(const char* event) {
  PetscLogEvent ev;
  PetscEventPerfInfo info{};
  if (PetscLogEventGetId(event, &ev) != 0 || PetscLogEventGetPerfInfo(0, ev, &info) != 0) return -1;
  return info.count;
}

inline hs::physics::SpaceOptions degree(int p) {
  hs::physics::SpaceOptions o;
  o.degree = p;
  return o;
}

/// Ascending eigenvalues of a (small) symmetric matrix, densely (LAPACK syev). Not collective.
inline std::vector<PetscScalar> dense_eigenvalues(Mat K) {
  Mat D;
  HS_PETSC(MatConvert(K, MATDENSE, MAT_INITIAL_MATRIX, &D));
  PetscInt n;
  HS_PETSC(MatGetSize(D, &n, nullptr));
  std::vector<PetscScalar> a(static_cast<std::size_t>(n * n)), w(static_cast<std::size_t>(n)),
      work(static_cast<std::size_t>(8 * n));
  {
    const PetscScalar* d;
    HS_PETSC(MatDenseGetArrayRead(D, &d));
    std::copy(d, d + n * n, a.begin());
    HS_PETSC(MatDenseRestoreArrayRead(D, &d));
  }
  HS_PETSC(MatDestroy(&D));
  PetscBLASInt bn = PetscBLASInt(n), lwork = PetscBLASInt(work.size()), info;
  LAPACKsyev_("N", "U", &bn, a.data(), &bn, w.data(), work.data(), &lwork, &info);
  if (info != 0) throw std::runtime_error("dense_eigenvalues: LAPACK syev failed");
  return w;
}

}  // namespace hstest
