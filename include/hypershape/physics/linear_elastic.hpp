#pragma once
/// Small-strain isotropic linear elasticity in the same interface as the hyperelastic kernels:
///   eps = sym(F - I),  W = mu eps:eps + lambda/2 (tr eps)^2,
///   P = sigma = 2 mu eps + lambda tr(eps) I,  A_iJkL = lambda d_iJ d_kL + mu (d_ik d_JL + d_iL d_Jk).
/// The residual is linear in u, so Newton converges in one step. In 2D this is plane strain
/// (eps_33 = 0). No det F guard (the linear problem has none); false only for non-finite F.
#include <cmath>
#include <vector>

#include "hypershape/physics/tensor.hpp"

namespace hypershape::physics {

template <int D>
struct LinearElastic {
  double mu = 0, lambda = 0;

  std::vector<double> constants() const { return {mu, lambda}; }
  static LinearElastic from_constants(const double* c) { return {c[0], c[1]}; }

  bool energy(const Tensor<D>& F, double& W) const {
    if (!std::isfinite(F.sum())) return false;
    const Tensor<D> e = strain(F);
    W = mu * e.squaredNorm() + 0.5 * lambda * e.trace() * e.trace();
    return true;
  }

  bool stress(const Tensor<D>& F, Tensor<D>& P) const {
    if (!std::isfinite(F.sum())) return false;
    const Tensor<D> e = strain(F);
    P = 2.0 * mu * e + (lambda * e.trace()) * Tensor<D>::Identity();
    return true;
  }

  bool stress_tangent(const Tensor<D>& F, Tensor<D>& P, Tangent<D>& A) const {
    if (!stress(F, P)) return false;
    for (int i = 0; i < D; ++i)
      for (int J = 0; J < D; ++J)
        for (int k = 0; k < D; ++k)
          for (int L = 0; L < D; ++L)
            A(i * D + J, k * D + L) = lambda * (i == J) * (k == L) + mu * ((i == k) * (J == L) + (i == L) * (J == k));
    return true;
  }

 private:
  static Tensor<D> strain(const Tensor<D>& F) {
    return 0.5 * (F + F.transpose()) - Tensor<D>::Identity();
  }
};

}  // namespace hypershape::physics
