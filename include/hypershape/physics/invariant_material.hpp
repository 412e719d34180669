#pragma once
/// Isotropic hyperelastic kernels from a stored energy W(I1, I2, J) of the invariants of
/// C = F^T F (I1 = tr C, I2 = (I1^2 - tr C^2) / 2, J = det F), evaluated in 3D; in 2D the
/// deformation gradient is embedded with F_33 = 1 (plane strain) and the in-plane parts of P
/// and A are returned. With G1 = dI1/dF = 2F, G2 = dI2/dF = 2(I1 F - F C), GJ = dJ/dF = J F^-T:
///   P = W_1 G1 + W_2 G2 + W_J GJ,
///   A_iJkL = sum_ab W_ab Ga_iJ Gb_kL + 2 W_1 d_ik d_JL
///          + 2 W_2 (2 F_iJ F_kL + I1 d_ik d_JL - d_ik C_LJ - F_iL F_kJ - b_ik d_JL)
///          + W_J J (F^-1_Ji F^-1_Lk - F^-1_Li F^-1_Jk),                     b = F F^T.
/// A model supplies W and its derivatives; a material file is then its energy only. Pure,
/// allocation-free, fixed-size; false (outputs untouched) if J <= 0 or not finite.
#include <Eigen/Dense>
#include <cmath>

#include "hypershape/physics/tensor.hpp"

namespace hypershape::physics {

/// W(I1, I2, J) and its first (d[a]) and second (dd[a][b]) derivatives, a in (I1, I2, J).
struct InvariantDerivatives {
  double W = 0;
  double d[3] = {0, 0, 0};
  double dd[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
};

namespace detail {

template <int D>
Tensor<3> embed3(const Tensor<D>& F) {
  Tensor<3> F3 = Tensor<3>::Identity();
  F3.template topLeftCorner<D, D>() = F;
  return F3;
}

struct Invariants {
  double I1, I2, J;
};

inline Invariants invariants(const Tensor<3>& F, const Tensor<3>& C) {
  const double I1 = C.trace();
  return {I1, 0.5 * (I1 * I1 - (C * C).trace()), F.determinant()};
}

/// The three first derivatives G1, G2, GJ of the invariants with respect to F.
inline void invariant_gradients(const Tensor<3>& F, const Tensor<3>& C, const Tensor<3>& FinvT,
                                const Invariants& v, Tensor<3> G[3]) {
  G[0] = 2.0 * F;
  G[1] = 2.0 * (v.I1 * F - F * C);
  G[2] = v.J * FinvT;
}

}  // namespace detail

/// Kernel family K<D> (see hyperelastic.hpp) from a model with
///   bool evaluate(double I1, double I2, double J, InvariantDerivatives& out) const.
template <class Model, int D>
struct InvariantKernel {
  Model model;

  bool energy(const Tensor<D>& F, double& W) const {
    const Tensor<3> F3 = detail::embed3<D>(F), C = F3.transpose() * F3;
    const detail::Invariants v = detail::invariants(F3, C);
    InvariantDerivatives w;
    if (!admissible(v) || !model.evaluate(v.I1, v.I2, v.J, w)) return false;
    W = w.W;
    return true;
  }

  bool stress(const Tensor<D>& F, Tensor<D>& P) const {
    Tangent<D> unused;
    return evaluate(F, P, unused, false);
  }

  bool stress_tangent(const Tensor<D>& F, Tensor<D>& P, Tangent<D>& A) const {
    return evaluate(F, P, A, true);
  }

 private:
  static bool admissible(const detail::Invariants& v) { return v.J > 0 && std::isfinite(v.I1); }

  bool evaluate(const Tensor<D>& F, Tensor<D>& P, Tangent<D>& A, bool tangent) const {
    const Tensor<3> F3 = detail::embed3<D>(F), C = F3.transpose() * F3;
    const detail::Invariants v = detail::invariants(F3, C);
    InvariantDerivatives w;
    if (!admissible(v) || !model.evaluate(v.I1, v.I2, v.J, w)) return false;
    const Tensor<3> Fi = F3.inverse();
    Tensor<3> G[3];
    detail::invariant_gradients(F3, C, Fi.transpose(), v, G);
    const Tensor<3> P3 = w.d[0] * G[0] + w.d[1] * G[1] + w.d[2] * G[2];
    P = P3.template topLeftCorner<D, D>();
    if (tangent) fill_tangent(F3, C, Fi, v, w, G, A);
    return true;
  }

  static void fill_tangent(const Tensor<3>& F, const Tensor<3>& C, const Tensor<3>& Fi,
                           const detail::Invariants& v, const InvariantDerivatives& w,
                           const Tensor<3> G[3], Tangent<D>& A) {
    const Tensor<3> b = F * F.transpose();
    for (int i = 0; i < D; ++i)
      for (int J = 0; J < D; ++J)
        for (int k = 0; k < D; ++k)
          for (int L = 0; L < D; ++L) {
            double a = 0;
            for (int p = 0; p < 3; ++p)
              for (int q = 0; q < 3; ++q) a += w.dd[p][q] * G[p](i, J) * G[q](k, L);
            const double ik = i == k, JL = J == L;
            a += 2.0 * w.d[0] * ik * JL;
            a += 2.0 * w.d[1] * (2.0 * F(i, J) * F(k, L) + v.I1 * ik * JL - ik * C(L, J) -
                                 F(i, L) * F(k, J) - b(i, k) * JL);
            a += w.d[2] * v.J * (Fi(J, i) * Fi(L, k) - Fi(L, i) * Fi(J, k));
            A(i * D + J, k * D + L) = a;
          }
  }
};

}  // namespace hypershape::physics
