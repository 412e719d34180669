#include "hypershape/solver/error_estimate.hpp"

#include <petscksp.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <initializer_list>
#include <stdexcept>
#include <unordered_map>

#include "hypershape/core/error.hpp"
#include "hypershape/core/vec_array.hpp"
#include "hypershape/mesh/reference_cell.hpp"
#include "hypershape/solver/ldlt.hpp"
#include "hypershape/solver/local_relaxation.hpp"
#include "log_events.hpp"

namespace hypershape::solver {

using physics::Problem;
using physics::Space;

namespace {

double factorial(int n) {
  double f = 1;
  for (int i = 2; i <= n; ++i) f *= i;
  return f;
}

/// int_T prod lambda_i^{a_i} / |T| = d! prod a_i! / (d + sum a)!.
double monomial_mean(int dim, const std::array<int, 4>& a) {
  double num = factorial(dim);
  int s = 0;
  for (int x : a) num *= factorial(x), s += x;
  return num / factorial(dim + s);
}

/// Cell measure of the simplex with vertex ids v (straight-sided).
double cell_measure(int dim, const std::vector<double>& x, const std::int64_t* v) {
  double e[3][3];
  for (int i = 0; i < dim; ++i)
    for (int k = 0; k < dim; ++k) e[i][k] = x[std::size_t(v[i + 1] * dim + k)] - x[std::size_t(v[0] * dim + k)];
  const double det = dim == 2 ? e[0][0] * e[1][1] - e[0][1] * e[1][0]
                              : e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) -
                                    e[0][1] * (e[1][0] * e[2][2] - e[1][2] * e[2][0]) +
                                    e[0][2] * (e[1][0] * e[2][1] - e[1][1] * e[2][0]);
  return std::abs(det) / factorial(dim);
}

/// Values of the P1/P2 basis (VTK order) at barycentric coordinates `l` (dim + 1 of them).
void basis_at(int dim, int degree, const double* l, double* n) {
  for (int a = 0; a <= dim; ++a) n[a] = degree == 1 ? l[a] : l[a] * (2 * l[a] - 1);
  if (degree == 1) return;
  int e = dim + 1;
  for (const auto& [a, b] : mesh::edges(dim)) n[e++] = 4 * l[a] * l[b];
}

bool finite_all(std::initializer_list<double> v) {
  for (double x : v)
    if (!std::isfinite(x)) return false;
  return true;
}


/// Global index of every (canonical node, component) of the space, -1 where constrained; the
/// same vector on every rank. Collective.
std::vector<PetscInt> global_indices(const Space& s) {
  const int d = s.dim();
  std::vector<PetscInt> out(std::size_t(s.n_nodes_global() * d), -1);
  std::unordered_map<PetscInt, std::int64_t> canonical_of;
  for (const auto& n : s.owned_nodes()) canonical_of[n.offset] = n.canonical;
  PetscSection ls, gs;
  HS_PETSC(DMGetLocalSection(s.dm(), &ls));
  HS_PETSC(DMGetGlobalSection(s.dm(), &gs));
  PetscInt p0, p1;
  HS_PETSC(PetscSectionGetChart(ls, &p0, &p1));
  for (PetscInt p = p0; p < p1; ++p) {
    PetscInt dof, off, goff, ncon;
    HS_PETSC(PetscSectionGetDof(ls, p, &dof));
    if (dof == 0) continue;
    HS_PETSC(PetscSectionGetOffset(gs, p, &goff));
    if (goff < 0) continue;  // a ghost: its owner numbers it
    HS_PETSC(PetscSectionGetOffset(ls, p, &off));
    auto it = canonical_of.find(off);
    if (it == canonical_of.end()) continue;
    HS_PETSC(PetscSectionGetConstraintDof(ls, p, &ncon));
    const PetscInt* con = nullptr;
    if (ncon > 0) HS_PETSC(PetscSectionGetConstraintIndices(ls, p, &con));
    PetscInt next = goff;
    for (int k = 0; k < d; ++k) {
      const bool fixed = con && std::find(con, con + ncon, k) != con + ncon;
      out[std::size_t(it->second * d + k)] = fixed ? -1 : next++;
    }
  }
  MPI_Allreduce(MPI_IN_PLACE, out.data(), int(out.size()), MPIU_INT, MPI_MAX, s.comm());
  return out;
}

template <class T>
void broadcast(std::vector<T>& v, MPI_Datatype type, MPI_Comm comm) {
  auto n = std::int64_t(v.size());
  MPI_Bcast(&n, 1, MPI_INT64_T, 0, comm);
  v.resize(std::size_t(n));
  MPI_Bcast(v.data(), int(n), type, 0, comm);
}

/// M_ab = int_T N_a N_b / |T| for the P1/P2 basis (VTK order): the same matrix on every
/// straight-sided simplex, so u^2 integrates exactly as |T| c^T M c (c: the cell's nodal values).
std::vector<double> mean_mass_matrix(int dim, int degree) {
  const int nv = dim + 1, npc = mesh::nodes_per_cell(dim, degree);
  // N_a = sum_ij C^a_ij l_i l_j, homogeneous in the barycentric l (sum l = 1): P1's l_a is
  // l_a sum_j l_j; P2's vertex function l_a (2 l_a - 1) = l_a^2 - sum_{b != a} l_a l_b, its
  // edge function 4 l_a l_b. Then int N_a N_b / |T| = sum C^a_ij C^b_qr mean(l_i l_j l_q l_r).
  using Coefficients = std::array<std::array<double, 4>, 4>;
  std::vector<Coefficients> C(static_cast<std::size_t>(npc), Coefficients{});
  for (int a = 0; a < nv; ++a)
    for (int b = 0; b < nv; ++b) {
      auto& c = C[std::size_t(a)];
      if (degree == 1) {
        c[std::size_t(a)][std::size_t(b)] += 0.5, c[std::size_t(b)][std::size_t(a)] += 0.5;
      } else if (b == a) {
        c[std::size_t(a)][std::size_t(a)] += 1;
      } else {
        c[std::size_t(a)][std::size_t(b)] -= 0.5, c[std::size_t(b)][std::size_t(a)] -= 0.5;
      }
    }
  if (degree == 2) {
    int e = nv;
    for (const auto& [a, b] : mesh::edges(dim)) {
      auto& c = C[std::size_t(e++)];
      c[std::size_t(a)][std::size_t(b)] = c[std::size_t(b)][std::size_t(a)] = 2;
    }
  }
  std::vector<double> M(std::size_t(npc * npc), 0.0);
  for (int x = 0; x < npc; ++x)
    for (int y = 0; y < npc; ++y)
      for (int i = 0; i < nv; ++i)
        for (int j = 0; j < nv; ++j)
          for (int q = 0; q < nv; ++q)
            for (int r = 0; r < nv; ++r) {
              std::array<int, 4> m{};
              ++m[std::size_t(i)], ++m[std::size_t(j)], ++m[std::size_t(q)], ++m[std::size_t(r)];
              M[std::size_t(x * npc + y)] += C[std::size_t(x)][std::size_t(i)][std::size_t(j)] *
                                             C[std::size_t(y)][std::size_t(q)][std::size_t(r)] * monomial_mean(dim, m);
            }
  return M;
}

}  // namespace

std::vector<double> l2_norms_squared(int dim, int degree, const std::vector<double>& coords,
                                     const std::vector<std::int64_t>& cells,
                                     const std::vector<const std::vector<double>*>& fields, int n_comp) {
  const int npc = mesh::nodes_per_cell(dim, degree);
  const std::vector<double> M = mean_mass_matrix(dim, degree);
  std::vector<double> total(fields.size(), 0.0);
  const std::size_t n_cells = cells.size() / std::size_t(npc);
  double c[10];
  for (std::size_t cell = 0; cell < n_cells; ++cell) {
    const std::int64_t* v = &cells[cell * std::size_t(npc)];
    const double vol = cell_measure(dim, coords, v);  // once for all fields
    for (std::size_t f = 0; f < fields.size(); ++f)
      for (int k = 0; k < n_comp; ++k) {
        for (int a = 0; a < npc; ++a) c[a] = (*fields[f])[std::size_t(v[a] * n_comp + k)];
        double s = 0;
        for (int a = 0; a < npc; ++a) {
          double row = 0;
          for (int b = 0; b < npc; ++b) row += M[std::size_t(a * npc + b)] * c[b];
          s += c[a] * row;
        }
        total[f] += vol * s;
      }
  }
  return total;
}

double l2_norm_squared(int dim, int degree, const std::vector<double>& coords, const std::vector<std::int64_t>& cells,
                       const std::vector<double>& field, int n_comp) {
  return l2_norms_squared(dim, degree, coords, cells, {&field}, n_comp)[0];
}

namespace {

/// The prolongation in canonical numbering (rank 0): for each fine node the coarse nodes and
/// basis values at its position in its parent cell.
void prolongation_rows(const Space& cs, const Space& fs, const mesh::RefinedMesh& refined,
                       std::vector<std::int64_t>& row, std::vector<std::int64_t>& col, std::vector<double>& w) {
  const int d = cs.dim(), p = cs.degree(), nv = d + 1, npc = mesh::nodes_per_cell(d, p);
  const auto& fc = fs.canonical_cells();
  const auto& cc = cs.canonical_cells();
  const std::size_t n_fine_cells = fc.size() / std::size_t(npc);
  if (n_fine_cells != refined.parent.size()) throw std::logic_error("TwoLevelEstimator: fine mesh is not the refined one");
  std::vector<std::vector<std::pair<std::int64_t, double>>> rows(std::size_t(fs.n_nodes_global()));
  std::vector<char> done(rows.size(), 0);
  for (std::size_t k = 0; k < n_fine_cells; ++k) {
    const std::int64_t c = refined.parent[k];
    const int* fin = &refined.mesh.cells[k * std::size_t(nv)];                 // the fine cell, input order
    const int* cin = &refined.coarse_cells[std::size_t(c) * std::size_t(nv)];  // its parent, input order
    const double* bary = &refined.bary[k * std::size_t(nv * nv)];
    const std::int64_t* fnode = &fc[k * std::size_t(npc)];
    const std::int64_t* cnode = &cc[std::size_t(c) * std::size_t(npc)];
    // Barycentric coordinates of each fine node in the parent's canonical vertex order.
    std::array<std::array<double, 4>, 10> lam{};
    for (int j = 0; j < nv; ++j) {
      const int t = int(std::find(fin, fin + nv, int(fnode[j])) - fin);
      if (t == nv) throw std::logic_error("TwoLevelEstimator: fine cell vertices differ from the refined mesh's");
      for (int i = 0; i < nv; ++i) {
        const int s = int(std::find(cin, cin + nv, int(cnode[i])) - cin);
        if (s == nv) throw std::logic_error("TwoLevelEstimator: coarse cell vertices differ from the mesh's");
        lam[std::size_t(j)][std::size_t(i)] = bary[t * nv + s];
      }
    }
    if (p == 2) {
      int e = nv;
      for (const auto& [a, b] : mesh::edges(d)) {
        for (int i = 0; i < nv; ++i) lam[std::size_t(e)][std::size_t(i)] = 0.5 * (lam[std::size_t(a)][std::size_t(i)] + lam[std::size_t(b)][std::size_t(i)]);
        ++e;
      }
    }
    for (int j = 0; j < npc; ++j) {
      const auto node = std::size_t(fnode[j]);
      if (done[node]) continue;
      done[node] = 1;
      double n[10];
      basis_at(d, p, lam[std::size_t(j)].data(), n);
      for (int a = 0; a < npc; ++a)
        if (std::abs(n[a]) > 1e-14) rows[node].push_back({cnode[a], n[a]});
    }
  }
  row.assign(1, 0);
  for (const auto& r : rows) {
    for (const auto& [cidx, wt] : r) col.push_back(cidx), w.push_back(wt);
    row.push_back(std::int64_t(col.size()));
  }
}

}  // namespace

TwoLevelEstimator::TwoLevelEstimator(const Problem& coarse, const Problem& fine, const mesh::RefinedMesh& refined,
                                     bool newton_to_tolerance)
    : coarse_(coarse), fine_(fine), newton_to_tolerance_(newton_to_tolerance) {
  const Space& cs = coarse.space();
  const Space& fs = fine.space();
  const int d = cs.dim();
  if (fs.degree() != cs.degree() || fs.dim() != d) throw std::logic_error("TwoLevelEstimator: spaces of different degree");
  if (core::rank(cs.comm()) == 0) prolongation_rows(cs, fs, refined, row_, col_, w_);
  broadcast(row_, MPI_INT64_T, cs.comm());
  broadcast(col_, MPI_INT64_T, cs.comm());
  broadcast(w_, MPI_DOUBLE, cs.comm());
  // P in global dofs: a row per free fine dof owned here, a column per free coarse dof.
  const std::vector<PetscInt> gf = global_indices(fs), gc = global_indices(cs);
  core::VecH vf = fine.create_vector(), vc = coarse.create_vector();
  PetscInt mf, mc;
  HS_PETSC(VecGetLocalSize(vf, &mf));
  HS_PETSC(VecGetLocalSize(vc, &mc));
  const PetscInt per_row = mesh::nodes_per_cell(d, cs.degree());
  HS_PETSC(MatCreateAIJ(fs.comm(), mf, mc, PETSC_DETERMINE, PETSC_DETERMINE, per_row, nullptr, per_row, nullptr, P_.out()));
  for (const auto& node : fs.owned_nodes()) {
    const auto i = std::size_t(node.canonical);
    for (int k = 0; k < d; ++k) {
      const PetscInt r = gf[i * std::size_t(d) + std::size_t(k)];
      if (r < 0) continue;
      for (auto q = row_[i]; q < row_[i + 1]; ++q) {
        const PetscInt c = gc[std::size_t(col_[std::size_t(q)] * d + k)];
        if (c >= 0) HS_PETSC(MatSetValue(P_, r, c, w_[std::size_t(q)], INSERT_VALUES));
      }
    }
  }
  HS_PETSC(MatAssemblyBegin(P_, MAT_FINAL_ASSEMBLY));
  HS_PETSC(MatAssemblyEnd(P_, MAT_FINAL_ASSEMBLY));
}

TwoLevelEstimator::~TwoLevelEstimator() = default;

void TwoLevelEstimator::prolong(Vec coarse, Vec fine) const { HS_PETSC(MatMult(P_, coarse, fine)); }

std::vector<double> TwoLevelEstimator::prolong(const std::vector<double>& cv) const {
  const int d = coarse_.space().dim();
  std::vector<double> out;
  if (cv.empty() || row_.empty()) return out;
  out.assign((row_.size() - 1) * std::size_t(d), 0.0);
  for (std::size_t i = 0; i + 1 < row_.size(); ++i)
    for (auto k = row_[i]; k < row_[i + 1]; ++k)
      for (int c = 0; c < d; ++c)
        out[i * std::size_t(d) + std::size_t(c)] += w_[std::size_t(k)] * cv[std::size_t(col_[std::size_t(k)] * d + c)];
  return out;
}

namespace {

/// GMRES with the two-grid preconditioner (CG stopped on indefinite fine tangents at prolonged states
/// of Random2D load cases): coarse level a PC shell (`coarse_apply`, context `ctx`),
/// interpolation P, one symmetric Gauss-Seidel sweep before and after on the fine level
/// (Richardson/SOR: no eigenvalue estimate per operator, which Chebyshev/Jacobi spent ten fine
/// products on at every estimate). Options with prefix "error_estimate_".
constexpr PetscInt kFineKrylovBudget = 40;

core::KSPH two_grid_solver(MPI_Comm comm, Mat Kf, Mat Kc, Mat P, PetscErrorCode (*coarse_apply)(PC, Vec, Vec), void* ctx) {
  core::KSPH ksp;
  HS_PETSC(KSPCreate(comm, ksp.out()));
  // The prefix before PCMGSetLevels: the levels' solvers take it when they are made (set after,
  // the smoothers read the global -mg_levels_* options and not -error_estimate_mg_levels_*).
  HS_PETSC(KSPSetOptionsPrefix(ksp, "error_estimate_"));
  HS_PETSC(KSPSetType(ksp, KSPGMRES));
  HS_PETSC(KSPSetOperators(ksp, Kf, Kf));
  // A budget of 40 unrestarted iterations; a step that spends it is kept (fine_step). On the
  // random3d preset's mean-dilatation tangents (nu 0.49: a stiff rank-one bulk term per cell that
  // the point smoother barely touches) GMRES to rtol 1e-2 took a median 32 and up to 300
  // iterations; stopped at 40, the estimates moved by a median 0% (p10-p90 -12% to +5%) and cost
  // half as much (docs/ACCURACY.md). A vertex-star Schwarz smoother was tried against the bulk
  // term and diverged: the fine tangent at P u_h is indefinite on 2% of the stars.
  HS_PETSC(KSPSetTolerances(ksp, 1e-2, 1e-30, PETSC_DEFAULT, kFineKrylovBudget));
  HS_PETSC(KSPGMRESSetRestart(ksp, kFineKrylovBudget));
  PC pc;
  HS_PETSC(KSPGetPC(ksp, &pc));
  HS_PETSC(PCSetType(pc, PCMG));
  HS_PETSC(PCMGSetLevels(pc, 2, nullptr));
  HS_PETSC(PCMGSetType(pc, PC_MG_MULTIPLICATIVE));
  HS_PETSC(PCMGSetGalerkin(pc, PC_MG_GALERKIN_NONE));
  HS_PETSC(PCMGSetInterpolation(pc, 1, P));
  KSP coarse, smooth;
  HS_PETSC(PCMGGetCoarseSolve(pc, &coarse));
  HS_PETSC(KSPSetOperators(coarse, Kc, Kc));
  HS_PETSC(KSPSetType(coarse, KSPPREONLY));
  PC cpc;
  HS_PETSC(KSPGetPC(coarse, &cpc));
  HS_PETSC(PCSetType(cpc, PCSHELL));
  HS_PETSC(PCShellSetContext(cpc, ctx));
  HS_PETSC(PCShellSetApply(cpc, coarse_apply));
  HS_PETSC(PCMGGetSmoother(pc, 1, &smooth));
  HS_PETSC(KSPSetType(smooth, KSPRICHARDSON));
  HS_PETSC(KSPSetTolerances(smooth, PETSC_DEFAULT, PETSC_DEFAULT, PETSC_DEFAULT, 1));
  PC spc;
  HS_PETSC(KSPGetPC(smooth, &spc));
  HS_PETSC(PCSetType(spc, PCSOR));
  HS_PETSC(KSPSetFromOptions(ksp));
  return ksp;
}

/// max over nodes of |v| and the node where it is.
double max_node(const std::vector<double>& v, int d, std::size_t* at = nullptr) {
  double m = -1;
  for (std::size_t i = 0; i + std::size_t(d) <= v.size(); i += std::size_t(d)) {
    double a = 0;
    for (int k = 0; k < d; ++k) a += v[i + std::size_t(k)] * v[i + std::size_t(k)];
    if (a > m) {
      m = a;
      if (at) *at = i / std::size_t(d);
    }
  }
  return std::sqrt(std::max(m, 0.0));
}

/// The estimates on rank 0 from canonical arrays: u_h (uc) and P u_h (pu), the fine step e (ev)
/// and du/dalpha (av): {rel L2, raw rel L2, max, raw max, slope, ok}.
std::array<double, 6> estimate_values(const Space& fs, const std::vector<double>& pu, const std::vector<double>& uc,
                                      const std::vector<double>& ev, const std::vector<double>& av, double theta,
                                      double alpha) {
  const int d = fs.dim(), p = fs.degree();
  std::array<double, 6> vals{};
  std::vector<double> uf(pu.size()), uf1(pu.size()), te(ev.size());
  for (std::size_t i = 0; i < pu.size(); ++i)
    te[i] = theta * ev[i], uf[i] = pu[i] + te[i], uf1[i] = pu[i] + ev[i];
  const auto& x = fs.canonical_coords();
  const auto& cells = fs.canonical_cells();
  const std::vector<double> n2 = l2_norms_squared(d, p, x, cells, {&ev, &uf, &uf1}, d);  // one pass
  const double ee = n2[0];
  const double mp = max_node(pu, d);
  vals[0] = std::sqrt(theta * theta * ee / n2[1]);
  vals[1] = std::sqrt(ee / n2[2]);
  vals[2] = mp > 0 ? (max_node(uf, d) - mp) / mp : 0;
  vals[3] = mp > 0 ? (max_node(uf1, d) - mp) / mp : 0;
  // dmax/dalpha at the node of max |u_h|: (u_k / |u_k|) . a_k.
  std::size_t km = 0;
  const double mh = max_node(uc, d, &km);
  double slope = 0;
  for (int k = 0; k < d && mh > 0; ++k) slope += uc[km * std::size_t(d) + std::size_t(k)] / mh * av[km * std::size_t(d) + std::size_t(k)];
  if (!(slope > 0) || !std::isfinite(slope)) slope = alpha != 0 ? mh / alpha : 0;  // the secant
  vals[4] = slope;
  vals[5] = finite_all({vals[0], vals[1], vals[2], vals[3], vals[4]}) ? 1 : 0;
  return vals;
}

}  // namespace

double TwoLevelEstimator::energy_search(Vec x, double ex, Vec dx, double alpha, Vec w, double& ew,
                                        ErrorEstimate& out) const {
  // Accept the largest step (halving) that lowers the potential energy: residual norms
  // rejected every step of one Random2D case, where the full step overshot 8x.
  LogEvent logged(events().estimate_fine_assembly);
  const double t = MPI_Wtime();
  double accepted = 0;
  for (double lambda = 1.0; lambda > 0.03 && accepted == 0; lambda *= 0.5) {
    HS_PETSC(VecWAXPY(w, lambda, dx, x));
    // (or leaves it at round-off: a u_h the fine space already solves has e = 0)
    if (fine_.energy(w, alpha, ew) && (ew < ex || std::abs(ew - ex) <= 1e-12 * std::abs(ex))) accepted = lambda;
  }
  out.seconds_assembly += MPI_Wtime() - t;
  return accepted;
}

namespace {

/// f() timed into acc and logged as `event`; its result.
template <class F>
bool timed(double& acc, PetscLogEvent event, F&& f) {
  LogEvent logged(event);
  const double t = MPI_Wtime();
  const bool ok = f();
  acc += MPI_Wtime() - t;
  return ok;
}

}  // namespace

double TwoLevelEstimator::fine_step(Vec x, double ex, Vec r, double alpha, bool first, bool& fell_back, double& ew,
                                    ErrorEstimate& out) const {
  Vec dx = fv_[2], w = fv_[3];
  out.tangent_assemblies += 1;
  if (!timed(out.seconds_assembly, events().estimate_fine_assembly, [&] { return fine_.jacobian(x, Kf_, alpha); })) {
    HS_PETSC(PetscInfo(ksp_.get(), "error estimate: fine tangent failed\n"));
    return -1;
  }
  HS_PETSC(KSPSetOperators(ksp_, Kf_, Kf_));
  HS_PETSC(VecScale(r, -1.0));
  timed(out.seconds_linear, events().estimate_fine_solve, [&] {
    HS_PETSC(KSPSolve(ksp_, r, dx));
    return true;
  });
  KSPConvergedReason reason;
  PetscInt its;
  HS_PETSC(KSPGetConvergedReason(ksp_, &reason));
  HS_PETSC(KSPGetIterationNumber(ksp_, &its));
  out.krylov_iterations += int(its);
  HS_PETSC(PetscInfo(ksp_.get(), "error estimate: fine step: KSP reason %d in %d its\n", int(reason), int(its)));
  // At the budget: GMRES's iterate (the least preconditioned residual over its space) is kept,
  // and the energy line search judges it as any step.
  if (reason == KSP_DIVERGED_ITS) out.krylov_budget_spent = true;
  if (reason <= 0 && reason != KSP_DIVERGED_ITS) return -1;
  double lambda = energy_search(x, ex, dx, alpha, w, ew, out);
  fell_back = false;
  if (lambda == 0 && first) {
    // No descent along the Newton step of an indefinite fine tangent (two Random2D load cases
    // of 44 once the step was solved to its tolerance): the two-grid preconditioner's own
    // step (a symmetric cycle on the coarse factor) instead, and Newton on from there (that
    // step alone gave half the u_{h/2} - u_h of a Random3D case).
    PC pc;
    HS_PETSC(KSPGetPC(ksp_, &pc));
    HS_PETSC(PCApply(pc, r, dx));
    lambda = energy_search(x, ex, dx, alpha, w, ew, out);
    fell_back = true;
  }
  return lambda;
}

bool TwoLevelEstimator::relax(Vec x, double alpha, Vec r, double& ex, PetscReal& rn, ErrorEstimate& out) const {
  PetscBool off = PETSC_FALSE;
  PetscOptionsGetBool(nullptr, nullptr, "-error_estimate_no_relaxation", &off, nullptr);
  if (off || !fine_.conservative() || core::size(fine_.space().comm()) > 1) return false;
  const double t = MPI_Wtime();  // counted with the fine assemblies (HSRelax in -log_view)
  if (!relaxation_) {
    PetscInt seeds = LocalRelaxation::kMaxSeeds << fine_.space().dim();
    PetscOptionsGetInt(nullptr, nullptr, "-error_estimate_relaxation_seeds", &seeds, nullptr);
    relaxation_ = std::make_unique<LocalRelaxation>(fine_, int(seeds));
    no_fixed_ = fine_.create_vector();
    HS_PETSC(VecZeroEntries(no_fixed_));
  }
  const LocalRelaxation::Result res = relaxation_->relax(x, alpha, r, no_fixed_);
  bool ok = true;
  if (res.relaxed) {
    ++out.relaxations;
    out.residual_assemblies += 1;
    ok = fine_.energy_residual(x, alpha, ex, r);
    HS_PETSC(VecNorm(r, NORM_2, &rn));
    HS_PETSC(PetscInfo(ksp_.get(), "error estimate: local relaxation: %d dofs, |R| there %g -> %g in %d steps; |R| %g\n",
                       res.dofs, res.before, res.after, res.iterations, double(rn)));
  }
  out.seconds_assembly += MPI_Wtime() - t;
  if (!ok) throw std::logic_error("a relaxed fine state is inadmissible");
  return res.relaxed;
}

bool TwoLevelEstimator::fine_newton(Vec Pu, double alpha, Vec e, ErrorEstimate& out) const {
  Vec x = fv_[0], r = fv_[1], w = fv_[3], g = fv_[4];
  HS_PETSC(VecCopy(Pu, x));
  out.residual_assemblies += 1;
  // The energy at x with its residual (one pass over the cells); after each step, the energy
  // the line search accepted.
  double ex = 0;
  if (!timed(out.seconds_assembly, events().estimate_fine_assembly, [&] {
        return fine_.conservative() ? fine_.energy_residual(x, alpha, ex, r)
                                    : fine_.residual(x, alpha, r) && fine_.energy(x, alpha, ex);
      })) {
    // The same field, sampled at other points of its cells: det F <= 0 there.
    out.inverted = true;
    HS_PETSC(PetscInfo(ksp_.get(), "error estimate: u_h inverts inside a cell (det F <= 0 at a refined-mesh quadrature point)\n"));
    return false;
  }
  PetscReal r0, rn, gn = 0;
  HS_PETSC(VecNorm(r, NORM_2, &r0));
  rn = r0;
  // Newton from P u_h: one step is the estimate to second order; further steps (at most 3, to
  // 1% of the first residual) after a step the energy line search had to cut (large
  // deformations, where a full step overshot: measured 8x too large an estimate on one
  // Random2D load case), and always with `newton_to_tolerance_` (the mean-dilatation element:
  // P u_h keeps each coarse cell's volume, not each fine cell's, and the first step mostly
  // restores those; measured on Random3D, the alpha estimate had the wrong sign on 8 of 9 load
  // cases after one step and was within 5% of the reference's after 3-4).
  //
  // A relaxation before the first step never ends the estimate, however far it lowers |R|: where
  // the residual of P u_h sits on a few nodes at a clamp's end it can fall below 1% of the first
  // there, while the global part of the error -- what these labels' estimates measure (the too
  // stiff discrete body) -- is still unseen (measured, 2026-12-02: an estimate of 6e-7 for a
  // Random2D label whose neighbours estimated 4e-3). At least one global step follows it.
  bool full_step = true;
  for (int it = 0; it < 4 && (it == 0 || !full_step || newton_to_tolerance_) && rn > 1e-2 * r0; ++it) {
    if (relax(x, alpha, r, ex, rn, out) && it > 0 && rn <= 1e-2 * r0) break;
    bool fell_back = false;
    double ew = 0;
    const double lambda = fine_step(x, ex, r, alpha, it == 0, fell_back, ew, out);
    HS_PETSC(PetscInfo(ksp_.get(), "error estimate: fine Newton step %d: |R| %g (first %g), step length %g%s\n", it,
                       double(rn), double(r0), lambda, fell_back ? " (the preconditioner's step)" : ""));
    if (lambda < 0) return false;
    const bool accepted = lambda > 0;
    full_step = full_step && lambda == 1.0 && !fell_back;
    // No descent after an accepted (cut) step: keep that state (flagged: not converged). With
    // the better-converged steps of the SOR smoother, two first load cases of 18 (Random2D
    // shapes 2 and 5) found none at their second step, round-off near the minimum.
    if (!accepted && it > 0) break;
    if (!accepted) {
      HS_PETSC(PetscInfo(ksp_.get(), "error estimate: no energy descent along the fine Newton step nor the preconditioner's\n"));
      return false;
    }
    if (full_step && !newton_to_tolerance_) {  // done: one full step is the estimate (no residual needed after it)
      HS_PETSC(VecSwap(x, w));
      break;
    }
    out.residual_assemblies += 1;
    if (!timed(out.seconds_assembly, events().estimate_fine_assembly, [&] { return fine_.residual(w, alpha, g); }))
      return false;
    HS_PETSC(VecNorm(g, NORM_2, &gn));
    HS_PETSC(VecSwap(x, w));
    HS_PETSC(VecSwap(r, g));  // (swaps the values: fv_ keeps its vectors)
    rn = gn;
    ex = ew;
  }
  out.newton_steps_converged = rn <= 1e-2 * r0 || full_step;
  HS_PETSC(VecWAXPY(e, -1.0, Pu, x));
  return true;
}

void TwoLevelEstimator::coarse_apply(Vec x, Vec y, bool refined) const {
  bool ok = false;
  if (coarse_solve_) {
    ok = coarse_solve_(x, y, refined);
  } else {
    KSPConvergedReason reason;
    HS_PETSC(KSPSolve(direct_, x, y));
    HS_PETSC(KSPGetConvergedReason(direct_, &reason));
    ok = reason > 0;
  }
  if (!ok) {  // the estimate reports it (ok = false); GMRES sees a zero correction
    coarse_failed_ = true;
    HS_PETSC(VecZeroEntries(y));
  }
}

PetscErrorCode TwoLevelEstimator::apply_coarse(PC pc, Vec x, Vec y) {
  PetscFunctionBeginUser;
  const TwoLevelEstimator* self = nullptr;
  PetscCall(PCShellGetContext(pc, &self));
  try {
    self->coarse_apply(x, y, false);
  } catch (const std::exception&) {  // a PETSc error inside the caller's solve: no estimate
    self->coarse_failed_ = true;
    PetscCall(VecZeroEntries(y));
  }
  PetscFunctionReturn(0);
}

bool TwoLevelEstimator::prepare_coarse(Vec u_h, const CoarseSolve& coarse_solve, ErrorEstimate& out) const {
  coarse_solve_ = coarse_solve;
  coarse_failed_ = false;
  if (coarse_solve_) return true;
  const MPI_Comm comm = coarse_.space().comm();
  out.tangent_assemblies += 1;
  if (!coarse_.jacobian(u_h, Kc_)) return false;
  if (!direct_) {
    HS_PETSC(KSPCreate(comm, direct_.out()));
    HS_PETSC(KSPSetOptionsPrefix(direct_, "error_estimate_coarse_"));
    configure_direct_solver(direct_, comm, coarse_.space().dim(), coarse_.conservative());
  }
  HS_PETSC(KSPSetOperators(direct_, Kc_, Kc_));  // new values: a numeric refactorisation
  out.factorizations = 1;
  return true;
}

ErrorEstimate TwoLevelEstimator::estimate(Vec u_h, double alpha, const CoarseSolve& coarse_solve) const {
  LogEvent logged(events().estimate);
  ErrorEstimate out;
  const double t0 = MPI_Wtime();
  const Space& fs = fine_.space();
  const int d = fs.dim();
  const MPI_Comm comm = fs.comm();
  PetscReal order = 1.0;
  PetscOptionsGetReal(nullptr, nullptr, "-error_estimate_order", &order, nullptr);
  const double theta = 1.0 / (1.0 - std::pow(2.0, -double(order)));
  if (fv_.empty()) {
    for (int k = 0; k < 7; ++k) fv_.push_back(fine_.create_vector());
    du_dalpha_ = coarse_.create_vector();
    Kf_ = fine_.create_matrix();
    Kc_ = coarse_.create_matrix();  // the coarse level's operator (the shell does not read it)
    ksp_ = two_grid_solver(comm, Kf_, Kc_, P_, &TwoLevelEstimator::apply_coarse, const_cast<TwoLevelEstimator*>(this));
  }
  Vec Pu = fv_[5], e = fv_[6], a = du_dalpha_;
  prolong(u_h, Pu);
  HS_PETSC(VecZeroEntries(e));
  HS_PETSC(VecZeroEntries(a));
  bool ok = prepare_coarse(u_h, coarse_solve, out) && fine_newton(Pu, alpha, e, out);
  // du/dalpha = K_c^-1 f_ext on the coarse level's factor (a back-solve).
  if (ok) coarse_apply(coarse_.load(), a, true);
  if (coarse_failed_) HS_PETSC(PetscInfo(ksp_.get(), "error estimate: the coarse solve failed\n"));
  ok = ok && !coarse_failed_;
  coarse_solve_ = nullptr;
  LogEvent values(events().estimate_values);
  const std::vector<double> uc = coarse_.gather(u_h).values, ev = fine_.gather(e).values, av = coarse_.gather(a).values;
  std::array<double, 6> vals{};  // rel L2, raw rel L2, max, raw max, slope, ok
  std::vector<double> pu;
  if (core::rank(comm) == 0 && ok) pu = prolong(uc), vals = estimate_values(fs, pu, uc, ev, av, theta, alpha);
  MPI_Bcast(vals.data(), 6, MPI_DOUBLE, 0, comm);
  out.ok = vals[5] > 0.5;
  if (out.ok && !pu.empty()) {
    for (std::size_t i = 0; i < pu.size(); ++i) pu[i] += ev[i];
    out.fine_state = std::move(pu);
  }
  if (out.ok) {
    out.rel_l2 = vals[0], out.raw_rel_l2 = vals[1], out.max_u = vals[2], out.raw_max_u = vals[3];
    out.slope = vals[4];
    // The label's max|u| is the target; the exact solution's at this alpha is (1 + max_u) times
    // it: the traction for the target moves by -max_u target / (dmax/dalpha).
    const double mh = uc.empty() ? 0.0 : max_node(uc, d);
    double m = mh;
    MPI_Bcast(&m, 1, MPI_DOUBLE, 0, comm);
    out.alpha = out.slope > 0 && alpha != 0 ? -out.max_u * m / (alpha * out.slope) : 0;
  }
  out.seconds = MPI_Wtime() - t0;
  return out;
}

}  // namespace hypershape::solver
