#include "hypershape/solver/block_ldlt.hpp"

// PetscKernel_A_gets_inverse_A_2, exported by libpetsc; its header is one of the private ones
// Debian's petsc-dev installs. Using PETSc's own 2x2 inverse keeps D^-1 PETSc's to the bit.
#include <petsc/private/kernels/blockinvert.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>

#include "hypershape/core/error.hpp"

namespace hypershape::solver {

namespace {

/// Two doubles, one SSE register: every operation on it is one IEEE operation per lane.
using V2 = double __attribute__((vector_size(16)));

inline V2 load(const double* p) {
  V2 v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
inline void store(double* p, V2 v) { std::memcpy(p, &v, sizeof v); }

/// Four doubles: one AVX register where the CPU has it, two SSE ones where not; either way one
/// IEEE operation per lane (no fused multiply-add: the same numbers on every x86-64 machine).
using V4 = double __attribute__((vector_size(32)));
using Lanes = long long __attribute__((vector_size(32)));

/// v = p[0..4) (by reference: a V4 passed or returned by value would change the ABI without AVX).
[[gnu::always_inline]] inline void get(V4& v, const double* p) { std::memcpy(&v, p, sizeof v); }

/// The factor's arrays, for the elimination below (BlockLdlt2's members).
struct Arrays {
  PetscInt nb;
  const PetscInt *ai, *aj, *ui, *uj;
  double *d, *u, *row;
  PetscInt *next, *first;
};

/// row[col[j]] += the 2x2 product of the multiplier m and block j of one row of U (u, blocks
/// column-major), for j in [0, n), entry by entry in the order of PETSc's scalar kernel:
///   r0 += m0 u0 + m1 u1, r1 += m2 u0 + m3 u1, r2 += m0 u2 + m1 u3, r3 += m2 u2 + m3 u3.
[[gnu::always_inline]] inline void add_row(double* row, double m0, double m1, double m2, double m3, const double* u,
                                           const PetscInt* col, PetscInt n) {
  const V4 p = {m0, m2, m0, m2}, q = {m1, m3, m1, m3};
  for (PetscInt j = 0; j < n; ++j, u += 4) {
    double* r = row + 4 * col[j];
    V4 b, x;  // (copied, not returned: a V4 in a signature would change the ABI without AVX)
    std::memcpy(&b, u, sizeof b);
    std::memcpy(&x, r, sizeof x);
    const V4 even = __builtin_shuffle(b, Lanes{0, 0, 2, 2}), odd = __builtin_shuffle(b, Lanes{1, 1, 3, 3});
    x += p * even + q * odd;
    std::memcpy(r, &x, sizeof x);
  }
}

/// The numeric factorisation (BlockLdlt2::factorise), compiled twice: for AVX2 (without FMA) and
/// for the baseline, the one the CPU runs chosen at load time. False on a zero pivot.
[[gnu::target_clones("avx2", "default")]] bool eliminate(const Arrays& f, const PetscScalar* a) {
  // PETSc's default for its factorisations (PCFactor): an exactly zero first pivot of a 2x2
  // block is replaced by a tiny shift; a zero second pivot fails.
  const PetscReal shift = 100.0 * PETSC_MACHINE_EPSILON;
  std::fill(f.next, f.next + f.nb, f.nb);
  bool ok = true;
  for (PetscInt k = 0; k < f.nb; ++k) {
    // Row k of A into the dense work row (zero elsewhere: each row is cleared as it is stored).
    for (PetscInt j = f.ai[k]; j < f.ai[k + 1]; ++j) std::memcpy(f.row + 4 * f.aj[j], a + 4 * j, 4 * sizeof(double));
    double dk[4];
    std::memcpy(dk, f.row + 4 * k, sizeof dk);
    // Rows i < k with U(i, k) != 0, in the order they were linked: U(i, k) becomes the
    // multiplier m = -D_i^-1 U(i, k); D_k and the rest of row k get m times row i.
    for (PetscInt i = f.next[k]; i < k;) {
      const PetscInt after = f.next[i];
      if (after < k) {  // the next row's blocks are scattered in memory: ask for them early
        __builtin_prefetch(f.u + 4 * f.first[after]);
        __builtin_prefetch(f.d + 4 * after);
      }
      const PetscInt first = f.first[i];
      const double* di = f.d + 4 * i;
      double* uik = f.u + 4 * first;
      const double u0 = uik[0], u1 = uik[1], u2 = uik[2], u3 = uik[3];
      const double m0 = -(di[0] * u0 + di[2] * u1), m1 = -(di[1] * u0 + di[3] * u1),
                   m2 = -(di[0] * u2 + di[2] * u3), m3 = -(di[1] * u2 + di[3] * u3);
      dk[0] += m0 * u0 + m1 * u1;
      dk[1] += m2 * u0 + m3 * u1;
      dk[2] += m0 * u2 + m1 * u3;
      dk[3] += m2 * u2 + m3 * u3;
      uik[0] = m0, uik[1] = m1, uik[2] = m2, uik[3] = m3;  // (m in registers: no copy through memory)
      const PetscInt start = first + 1, end = f.ui[i + 1];
      if (start < end) {
        add_row(f.row, m0, m1, m2, m3, f.u + 4 * start, f.uj + start, end - start);
        f.first[i] = start;  // row i joins the list of its next column
        f.next[i] = f.next[f.uj[start]];
        f.next[f.uj[start]] = i;
      }
      i = after;
    }
    double* dinv = f.d + 4 * k;
    std::memcpy(dinv, dk, sizeof dk);
    PetscBool zero = PETSC_FALSE;
    HS_PETSC(PetscKernel_A_gets_inverse_A_2(dinv, shift, PETSC_TRUE, &zero));
    if (zero) ok = false;  // go on: the work row must end cleared
    const PetscInt start = f.ui[k], end = f.ui[k + 1];
    for (PetscInt p = start; p < end; ++p) {
      double* r = f.row + 4 * f.uj[p];
      std::memcpy(f.u + 4 * p, r, 4 * sizeof(double));
      std::fill(r, r + 4, 0.0);
    }
    if (start < end) {
      f.first[k] = start;
      f.next[k] = f.next[f.uj[start]];
      f.next[f.uj[start]] = k;
    }
  }
  return ok;
}

/// BlockLdlt2::solve2's substitutions, compiled as eliminate() is. Lanes (a0, a1, b0, b1) of a
/// node; each lane sums as solve() does: y0 += v0 x0 + v1 x1, y1 += v2 x0 + v3 x1 forward,
/// x0 += v0 y0 + v2 y1, x1 += v1 y0 + v3 y1 backward, D^-1 as d0 x0 + d2 x1, d1 x0 + d3 x1.
/// The factor as the substitutions read it (no work arrays, nothing written).
struct Factor {
  PetscInt nb;
  const PetscInt *ui, *uj;
  const double *d, *u;
};

[[gnu::target_clones("avx2", "default")]] void substitute2(const Factor& f, PetscScalar* x) {
  const Lanes even{0, 0, 2, 2}, odd{1, 1, 3, 3}, rows{0, 2, 0, 2}, cols{1, 3, 1, 3}, low{0, 1, 0, 1}, high{2, 3, 2, 3};
  for (PetscInt k = 0; k < f.nb; ++k) {
    V4 xk, v, yv, d;
    get(xk, x + 4 * k);
    const V4 x0 = __builtin_shuffle(xk, even), x1 = __builtin_shuffle(xk, odd);
    for (PetscInt p = f.ui[k]; p < f.ui[k + 1]; ++p) {
      double* y = x + 4 * f.uj[p];
      get(v, f.u + 4 * p);
      get(yv, y);
      yv += __builtin_shuffle(v, rows) * x0 + __builtin_shuffle(v, cols) * x1;
      std::memcpy(y, &yv, sizeof yv);
    }
    get(d, f.d + 4 * k);
    const V4 out = __builtin_shuffle(d, low) * x0 + __builtin_shuffle(d, high) * x1;
    std::memcpy(x + 4 * k, &out, sizeof out);
  }
  for (PetscInt k = f.nb - 1; k >= 0; --k) {
    V4 xk, v, y;
    get(xk, x + 4 * k);
    for (PetscInt p = f.ui[k]; p < f.ui[k + 1]; ++p) {
      get(v, f.u + 4 * p);
      get(y, x + 4 * f.uj[p]);
      xk += __builtin_shuffle(v, low) * __builtin_shuffle(y, even) + __builtin_shuffle(v, high) * __builtin_shuffle(y, odd);
    }
    std::memcpy(x + 4 * k, &xk, sizeof xk);
  }
}

}  // namespace

void BlockLdlt2::analyse(PetscInt nb, const PetscInt* rows, const PetscInt* cols) {
  nb_ = nb;
  ai_.assign(rows, rows + nb + 1);
  aj_.assign(cols, cols + rows[nb]);
  // Row k of U: the columns > k of A's row k and of U's rows whose first column is k (k's
  // children in the elimination tree), merged and sorted.
  std::vector<PetscInt> child_head(std::size_t(nb), -1), child_next(std::size_t(nb), -1), mark(std::size_t(nb), -1);
  std::vector<PetscInt> row;
  ui_.assign(std::size_t(nb) + 1, 0);
  uj_.clear();
  auto add = [&](PetscInt k, PetscInt c) {
    if (c > k && mark[std::size_t(c)] != k) mark[std::size_t(c)] = k, row.push_back(c);
  };
  for (PetscInt k = 0; k < nb; ++k) {
    row.clear();
    if (ai_[std::size_t(k)] == ai_[std::size_t(k) + 1] || aj_[std::size_t(ai_[std::size_t(k)])] != k)
      throw std::invalid_argument("BlockLdlt2: block row " + std::to_string(k) + " has no diagonal block first");
    for (PetscInt j = ai_[std::size_t(k)]; j < ai_[std::size_t(k) + 1]; ++j) add(k, aj_[std::size_t(j)]);
    for (PetscInt c = child_head[std::size_t(k)]; c >= 0; c = child_next[std::size_t(c)])
      for (PetscInt p = ui_[std::size_t(c)]; p < ui_[std::size_t(c) + 1]; ++p) add(k, uj_[std::size_t(p)]);
    std::sort(row.begin(), row.end());
    uj_.insert(uj_.end(), row.begin(), row.end());
    ui_[std::size_t(k) + 1] = PetscInt(uj_.size());
    if (!row.empty()) {
      child_next[std::size_t(k)] = child_head[std::size_t(row[0])];
      child_head[std::size_t(row[0])] = k;
    }
  }
  d_.assign(4 * std::size_t(nb), 0.0);
  u_.assign(4 * uj_.size(), 0.0);
  row_.assign(4 * std::size_t(nb), 0.0);
  next_.assign(std::size_t(nb), nb);
  first_.assign(std::size_t(nb), 0);
}

bool BlockLdlt2::factorise(const PetscScalar* a) {
  dabs_current_ = false;
  const Arrays f{nb_, ai_.data(), aj_.data(), ui_.data(), uj_.data(), d_.data(), u_.data(), row_.data(), next_.data(),
                 first_.data()};
  return eliminate(f, a);
}

void BlockLdlt2::solve(PetscScalar* x) const {
  // U^T D y = b forward (D^-1 applied as each block row is finished), then U x = y backward.
  for (PetscInt k = 0; k < nb_; ++k) {
    const double x0 = x[2 * k], x1 = x[2 * k + 1];
    for (PetscInt p = ui_[std::size_t(k)]; p < ui_[std::size_t(k) + 1]; ++p) {
      const double* v = &u_[4 * std::size_t(p)];
      double* y = x + 2 * uj_[std::size_t(p)];
      const V2 v01 = load(v), v23 = load(v + 2);
      const V2 a = __builtin_shuffle(v01, v23, (__attribute__((vector_size(16))) long){0, 2});  // v0, v2
      const V2 b = __builtin_shuffle(v01, v23, (__attribute__((vector_size(16))) long){1, 3});  // v1, v3
      store(y, load(y) + (a * x0 + b * x1));
    }
    const double* d = &d_[4 * std::size_t(k)];
    store(x + 2 * k, load(d) * x0 + load(d + 2) * x1);
  }
  for (PetscInt k = nb_ - 1; k >= 0; --k) {
    V2 xk = load(x + 2 * k);
    for (PetscInt p = ui_[std::size_t(k)]; p < ui_[std::size_t(k) + 1]; ++p) {
      const double* v = &u_[4 * std::size_t(p)];
      const double* y = x + 2 * uj_[std::size_t(p)];
      xk += load(v) * y[0] + load(v + 2) * y[1];
    }
    store(x + 2 * k, xk);
  }
}

void BlockLdlt2::solve2(PetscScalar* x) const {
  substitute2(Factor{nb_, ui_.data(), uj_.data(), d_.data(), u_.data()}, x);
}

void BlockLdlt2::solve2_absolute(PetscScalar* x) const {
  if (!dabs_current_) {
    dabs_.assign(d_.begin(), d_.end());
    for (PetscInt k = 0; k < nb_; ++k) {
      double* v = &dabs_[4 * std::size_t(k)];
      const double a = v[0], b = 0.5 * (v[1] + v[2]), d = v[3];
      if (a * d - b * b > 0 && a > 0) continue;
      const double mean = 0.5 * (a + d), radius = std::hypot(0.5 * (a - d), b);
      const double l1 = mean + radius, l2 = mean - radius;
      const double t = std::atan2(2 * b, a - d) / 2;
      const double c = std::cos(t), s = std::sin(t), m1 = std::abs(l1), m2 = std::abs(l2);
      v[0] = m1 * c * c + m2 * s * s;
      v[1] = v[2] = (m1 - m2) * c * s;
      v[3] = m1 * s * s + m2 * c * c;
    }
    dabs_current_ = true;
  }
  substitute2(Factor{nb_, ui_.data(), uj_.data(), dabs_.data(), u_.data()}, x);
}

int negative_eigenvalues_2x2(const PetscScalar* dinv, PetscInt nb) {
  int neg = 0;
  for (PetscInt k = 0; k < nb; ++k) {
    const double* v = dinv + 4 * k;
    const double a = v[0], b = 0.5 * (v[1] + v[2]), d = v[3];  // the block's symmetric part
    const double det = a * d - b * b;
    neg += det < 0 ? 1 : (det > 0 && a < 0 ? 2 : 0);
  }
  return neg;
}

int BlockLdlt2::negative_eigenvalues() const { return negative_eigenvalues_2x2(d_.data(), nb_); }

}  // namespace hypershape::solver
