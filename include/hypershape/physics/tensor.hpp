#pragma once
/// The fixed-size tensors of the pointwise kernels, shared by every material and by the
/// generic cell loops (hyperelastic.hpp): a second-order tensor (the deformation gradient F,
/// the first Piola-Kirchhoff stress P) and a fourth-order tangent dP/dF as a matrix, plus the
/// Lame parameters every isotropic material is written in.
#include <Eigen/Dense>

namespace hypershape::physics {

template <int D>
using Tensor = Eigen::Matrix<double, D, D>;
/// The tangent as a (D*D) x (D*D) matrix, A(i*D + J, k*D + L) = dP_iJ / dF_kL.
template <int D>
using Tangent = Eigen::Matrix<double, D * D, D * D>;

/// Lame parameters from Young's modulus and Poisson's ratio.
struct Lame {
  double mu, lambda;
  static Lame from_young_poisson(double E, double nu) {
    return {E / (2.0 * (1.0 + nu)), E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))};
  }
};

}  // namespace hypershape::physics
