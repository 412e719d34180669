#pragma once
/// The seed paper's compressible Neo-Hookean material (appendix A):
///   W(F) = mu/2 (tr(F^T F) - d - 2 ln J) + lambda/2 (ln J)^2,   J = det F,
///   P = dW/dF = mu (F - F^{-T}) + lambda ln J F^{-T},
///   A_{iJkL} = dP_{iJ}/dF_{kL} = mu d_ik d_JL + (mu - lambda ln J) F^{-1}_{Li} F^{-1}_{Jk}
///              + lambda F^{-1}_{Ji} F^{-1}_{Lk}.
/// In 2D this is plane strain (F_33 = 1 contributes tr 1 - 1 = 0). Pure, allocation-free,
/// fixed-size: every function returns false (and leaves outputs untouched) if J <= 0.
#include <Eigen/Dense>
#include <cmath>
#include <vector>

#include "hypershape/physics/tensor.hpp"

namespace hypershape::physics {

template <int D>
struct NeoHookean {
  double mu = 0, lambda = 0;

  /// The PETSc pointwise constants (mu, lambda) and back.
  std::vector<double> constants() const { return {mu, lambda}; }
  static NeoHookean from_constants(const double* c) { return {c[0], c[1]}; }

  bool energy(const Tensor<D>& F, double& W) const {
    const double J = F.determinant();
    if (!(J > 0)) return false;
    const double lnJ = std::log(J);
    W = 0.5 * mu * (F.squaredNorm() - D - 2.0 * lnJ) + 0.5 * lambda * lnJ * lnJ;
    return true;
  }

  bool stress(const Tensor<D>& F, Tensor<D>& P) const {
    const double J = F.determinant();
    if (!(J > 0)) return false;
    const Tensor<D> FinvT = F.inverse().transpose();
    P = mu * (F - FinvT) + (lambda * std::log(J)) * FinvT;
    return true;
  }

  /// energy() and stress() at once (det F, F^-1 and ln J computed once): the same numbers.
  bool energy_stress(const Tensor<D>& F, double& W, Tensor<D>& P) const {
    const double J = F.determinant();
    if (!(J > 0)) return false;
    const double lnJ = std::log(J);
    W = 0.5 * mu * (F.squaredNorm() - D - 2.0 * lnJ) + 0.5 * lambda * lnJ * lnJ;
    const Tensor<D> FinvT = F.inverse().transpose();
    P = mu * (F - FinvT) + (lambda * lnJ) * FinvT;
    return true;
  }

  // Inlined into the cell loops, where the tangent assembly drops the P it does not read.
  [[gnu::always_inline]] bool stress_tangent(const Tensor<D>& F, Tensor<D>& P, Tangent<D>& A) const {
    const double J = F.determinant();
    if (!(J > 0)) return false;
    const Tensor<D> Fi = F.inverse();
    const double lnJ = std::log(J);
    P = mu * (F - Fi.transpose()) + (lambda * lnJ) * Fi.transpose();
    const double c1 = mu - lambda * lnJ;
    for (int i = 0; i < D; ++i)
      for (int J_ = 0; J_ < D; ++J_)
        for (int k = 0; k < D; ++k)
          for (int L = 0; L < D; ++L)
            A(i * D + J_, k * D + L) = (i == k && J_ == L ? mu : 0.0) + c1 * Fi(L, i) * Fi(J_, k) +
                                       lambda * Fi(J_, i) * Fi(L, k);
    return true;
  }
};

}  // namespace hypershape::physics
