/// Nonlinear elimination of local trouble spots before the corrector's global Newton step: see
/// include/hypershape/solver/local_relaxation.hpp.
#include "hypershape/solver/local_relaxation.hpp"

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <numeric>

#include "hypershape/core/error.hpp"
#include "hypershape/core/vec_array.hpp"
#include "log_events.hpp"

namespace hypershape::solver {

std::vector<PetscInt> global_of_local_dofs(const physics::Problem& problem) {
  DM dm = problem.dm();
  core::VecH g = problem.create_vector();
  PetscInt lo, hi;
  HS_PETSC(VecGetOwnershipRange(g, &lo, &hi));
  {
    core::VecArray<PetscScalar> gv(g);
    for (PetscInt i = lo; i < hi; ++i) gv[i - lo] = PetscScalar(i);
  }
  Vec l;
  HS_PETSC(DMGetLocalVector(dm, &l));
  HS_PETSC(VecSet(l, -1.0));  // constrained entries: the global vector has none
  HS_PETSC(DMGlobalToLocal(dm, g, INSERT_VALUES, l));
  PetscInt n;
  HS_PETSC(VecGetLocalSize(l, &n));
  std::vector<PetscInt> out(std::size_t(n), -1);
  {
    core::VecArray<const PetscScalar> lv(l);
    for (PetscInt i = 0; i < n; ++i) {
      const auto k = PetscInt(std::llround(PetscRealPart(lv[i])));
      out[std::size_t(i)] = k >= lo && k < hi ? k : -1;  // owned entries only
    }
  }
  HS_PETSC(DMRestoreLocalVector(dm, &l));
  return out;
}

LocalRelaxation::LocalRelaxation(const physics::Problem& problem, int max_seeds)
    : problem_(problem), dim_(problem.space().dim()), max_seeds_(max_seeds), gol_(global_of_local_dofs(problem)) {
  const physics::Space& sp = problem.space();
  const PetscInt n_nodes = PetscInt(gol_.size()) / dim_;
  const int nb = sp.n_nodes();
  node_cells_ptr_.assign(std::size_t(n_nodes) + 1, 0);
  for (PetscInt c = sp.cell_begin(); c < sp.cell_end(); ++c)
    for (int a = 0; a < nb; ++a) ++node_cells_ptr_[std::size_t(sp.local_dofs(c)[a * dim_] / dim_) + 1];
  std::partial_sum(node_cells_ptr_.begin(), node_cells_ptr_.end(), node_cells_ptr_.begin());
  node_cells_.resize(std::size_t(node_cells_ptr_.back()));
  std::vector<PetscInt> fill(node_cells_ptr_.begin(), node_cells_ptr_.end() - 1);
  for (PetscInt c = sp.cell_begin(); c < sp.cell_end(); ++c)
    for (int a = 0; a < nb; ++a) node_cells_[std::size_t(fill[std::size_t(sp.local_dofs(c)[a * dim_] / dim_)]++)] = c;
  in_patch_.assign(std::size_t(sp.cell_end() - sp.cell_begin()), 0);
  PetscInt n_global;
  work_ = problem.create_vector();
  trial_ = problem.create_vector();
  HS_PETSC(VecGetSize(work_, &n_global));
  position_.assign(std::size_t(n_global), -1);
  K_ = problem.create_matrix();
}

void LocalRelaxation::patch(const std::vector<PetscInt>& seeds, const PetscScalar* fixed) {
  const physics::Space& sp = problem_.space();
  const PetscInt c0 = sp.cell_begin();
  for (const PetscInt c : cells_) in_patch_[std::size_t(c - c0)] = 0;
  for (const PetscInt g : free_) position_[std::size_t(g)] = -1;
  cells_.clear();
  free_.clear();
  auto add_cells_of = [&](PetscInt node) {
    for (PetscInt k = node_cells_ptr_[std::size_t(node)]; k < node_cells_ptr_[std::size_t(node) + 1]; ++k) {
      const PetscInt c = node_cells_[std::size_t(k)];
      if (!in_patch_[std::size_t(c - c0)]) {
        in_patch_[std::size_t(c - c0)] = 1;
        cells_.push_back(c);
      }
    }
  };
  // Rings of cells around the seeds: three in 2D, two in 3D. Measured (Newton iterations, solve +
  // alpha-search seconds, runs side by side): Random2D P2 seed 2024, 20 x 25, rings 1 / 2 / 3 / 4:
  // 5465 (499 converged) / 4524 / 4274 / 4186 iterations, 3 about 5% faster than 2; Random3D seed
  // 90210, 2 x 10: 2 / 3 rings 133 / 126 iterations but 33 / 42 s (patches of thousands of dofs).
  for (const PetscInt n : seeds) add_cells_of(n);
  for (int ring = 1; ring < (dim_ == 2 ? 3 : 2); ++ring) {
    const std::vector<PetscInt> inner = cells_;
    for (const PetscInt c : inner)
      for (int a = 0; a < sp.n_nodes(); ++a) add_cells_of(sp.local_dofs(c)[a * dim_] / dim_);
  }
  std::sort(cells_.begin(), cells_.end());
  // The free dofs: of the nodes whose every cell is in the patch (their residual is the patch's).
  for (const PetscInt c : cells_)
    for (int a = 0; a < sp.n_nodes(); ++a) {
      const PetscInt node = sp.local_dofs(c)[a * dim_] / dim_;
      bool inside = true;
      for (PetscInt k = node_cells_ptr_[std::size_t(node)]; inside && k < node_cells_ptr_[std::size_t(node) + 1]; ++k)
        inside = in_patch_[std::size_t(node_cells_[std::size_t(k)] - c0)] != 0;
      if (!inside) continue;
      for (int i = 0; i < dim_; ++i) {
        const PetscInt g = gol_[std::size_t(node * dim_ + i)];
        if (g < 0 || fixed[g] != 0.0 || position_[std::size_t(g)] >= 0) continue;
        position_[std::size_t(g)] = int(free_.size());
        free_.push_back(g);
      }
    }
}

bool LocalRelaxation::patch_residual(Vec u, double s, Eigen::VectorXd& rf) {
  {
    physics::CellSubset only(problem_.space(), cells_);
    if (!problem_.residual(u, s, work_)) return false;
  }
  core::VecArray<const PetscScalar> r(work_);
  rf.resize(Eigen::Index(free_.size()));
  for (std::size_t i = 0; i < free_.size(); ++i) rf[Eigen::Index(i)] = r[free_[i]];
  return true;
}

bool LocalRelaxation::patch_energy(Vec u, double s, double& e) {
  physics::CellSubset only(problem_.space(), cells_);
  return problem_.energy(u, s, e);
}

bool LocalRelaxation::seed_nodes(Vec r, std::vector<PetscInt>& seeds, double& total) const {
  core::VecArray<const PetscScalar> ra(r);
  const PetscInt n_nodes = PetscInt(gol_.size()) / dim_;
  std::vector<double> node2(std::size_t(n_nodes), 0.0);
  double largest = 0;
  total = 0;
  for (PetscInt n = 0; n < n_nodes; ++n) {
    for (int i = 0; i < dim_; ++i)
      if (const PetscInt g = gol_[std::size_t(n * dim_ + i)]; g >= 0) node2[std::size_t(n)] += ra[g] * ra[g];
    total += node2[std::size_t(n)];
    largest = std::max(largest, node2[std::size_t(n)]);
  }
  double seeded = 0;
  for (PetscInt n = 0; n < n_nodes; ++n)
    if (node2[std::size_t(n)] >= 0.01 * largest) {
      seeds.push_back(n);
      seeded += node2[std::size_t(n)];
    }
  const bool nothing_to_relax = !(largest > 0) || seeds.size() > std::size_t(max_seeds_) || seeded < 0.5 * total;
  return !nothing_to_relax;
}

/// The patch's tangent, sparse (a patch has hundreds of dofs in 2D, a thousand in 3D P2), and
/// its Cholesky factor (AMD ordering, the pattern analysed once per patch) of K + mu I, mu from 0
/// up until it is definite, so that the step descends on the patch's energy.
struct LocalRelaxation::PatchFactor {
  explicit PatchFactor(Eigen::Index n) : K(n, n) {}
  /// Factorises K (shifted where it is not definite); `diagonal` = sum |K_ii|. False where no
  /// shift up to 1e12 times the first made it definite.
  bool factorise(double diagonal, bool analyse) {
    if (analyse) llt.analyzePattern(K);
    const double mu0 = 1e-3 * diagonal / double(K.cols());
    llt.setShift(0.0);
    llt.factorize(K);
    for (double mu = mu0; llt.info() != Eigen::Success && mu < 1e12 * mu0; mu *= 4) {
      llt.setShift(mu);
      llt.factorize(K);
    }
    return llt.info() == Eigen::Success;
  }
  Eigen::SparseMatrix<double> K;
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Lower> llt;
  std::vector<Eigen::Triplet<double>> entries;
};

bool LocalRelaxation::patch_tangent(Vec u, double s, PatchFactor& f, double& diagonal) {
  {
    physics::CellSubset only(problem_.space(), cells_);
    if (!problem_.jacobian(u, K_, s)) return false;
  }
  f.entries.clear();
  diagonal = 0;
  for (Eigen::Index i = 0; i < f.K.cols(); ++i) {
    PetscInt ncols;
    const PetscInt* cols;
    const PetscScalar* vals;
    HS_PETSC(MatGetRow(K_, free_[std::size_t(i)], &ncols, &cols, &vals));
    for (PetscInt k = 0; k < ncols; ++k)
      if (const int j = position_[std::size_t(cols[k])]; j >= i) {
        f.entries.emplace_back(int(j), int(i), vals[k]);  // the lower triangle, column i
        if (j == i) diagonal += std::abs(vals[k]);
      }
    HS_PETSC(MatRestoreRow(K_, free_[std::size_t(i)], &ncols, &cols, &vals));
  }
  f.K.setFromTriplets(f.entries.begin(), f.entries.end());
  return true;
}

bool LocalRelaxation::descend(Vec u, double s, const Eigen::VectorXd& d, double slope, double& e0) {
  double lambda = 1.0, e = 0;
  for (; lambda > 1e-6; lambda *= 0.5) {
    HS_PETSC(VecCopy(u, trial_));
    {
      core::VecArray<PetscScalar> t(trial_);
      for (Eigen::Index i = 0; i < d.size(); ++i) t[free_[std::size_t(i)]] += lambda * d[i];
    }
    if (patch_energy(trial_, s, e) && e <= e0 + 1e-4 * lambda * slope) break;
  }
  if (!(lambda > 1e-6)) return false;
  HS_PETSC(VecCopy(trial_, u));
  e0 = e;
  return true;
}

LocalRelaxation::Result LocalRelaxation::relax(Vec u, double s, Vec r, Vec fixed) {
  LogEvent logged(events().relaxation);
  Result out;
  std::vector<PetscInt> seeds;
  double total = 0;
  if (!seed_nodes(r, seeds, total)) return out;
  {
    core::VecArray<const PetscScalar> fx(fixed);
    patch(seeds, fx.data());
  }
  const auto nf = Eigen::Index(free_.size());
  out.dofs = int(nf);
  if (nf == 0) return out;
  // The goal: a tenth of the residual outside the patch, or a hundredth of the patch's own.
  Eigen::VectorXd rv;
  if (!patch_residual(u, s, rv)) return out;
  out.before = out.after = rv.norm();
  const double outside = std::sqrt(std::max(total - rv.squaredNorm(), 0.0));
  const double goal = std::max(0.1 * outside, 1e-2 * out.before);
  constexpr int kMaxSteps = 10;
  PatchFactor f(nf);
  double e0 = NAN;  // the patch's energy at u: the accepted trial's after the first step
  for (; out.iterations < kMaxSteps && out.after > goal; ++out.iterations) {
    double diagonal;
    if (!patch_tangent(u, s, f, diagonal) || !f.factorise(diagonal, out.iterations == 0)) break;
    const Eigen::VectorXd d = -f.llt.solve(rv);
    const double slope = rv.dot(d);
    if (!(slope < 0) || (std::isnan(e0) && !patch_energy(u, s, e0))) break;
    if (!descend(u, s, d, slope, e0)) break;
    out.relaxed = true;
    if (!patch_residual(u, s, rv)) break;  // (admissible: its energy was finite)
    out.after = rv.norm();
  }
  return out;
}

}  // namespace hypershape::solver
