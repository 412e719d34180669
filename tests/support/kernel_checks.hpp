#pragma once
/// Shared helpers of the pointwise-kernel tests: random deformation gradients and rotations, and
/// 4th-order central differences in one component of F.
#include <Eigen/Dense>
#include <random>
#include <type_traits>

#include "hypershape/physics/neo_hookean.hpp"

namespace hstest {

using hypershape::physics::Tensor;

/// A random deformation gradient I + U(-spread, spread) per entry, with det F > min_det.
template <int D>
Tensor<D> random_f(std::mt19937_64& rng, double spread = 0.4, double min_det = 0.2) {
  std::uniform_real_distribution<double> u(-spread, spread);
  for (;;) {
    Tensor<D> F = Tensor<D>::Identity();
    for (int i = 0; i < D; ++i)
      for (int j = 0; j < D; ++j) F(i, j) += u(rng);
    if (F.determinant() > min_det) return F;
  }
}

/// A random rotation (det Q = +1).
template <int D>
Tensor<D> random_rotation(std::mt19937_64& rng) {
  std::normal_distribution<double> n;
  Tensor<D> M;
  for (int i = 0; i < D; ++i)
    for (int j = 0; j < D; ++j) M(i, j) = n(rng);
  Eigen::HouseholderQR<Tensor<D>> qr(M);
  Tensor<D> Q = qr.householderQ();
  if (Q.determinant() < 0) Q.col(0) *= -1.0;
  return Q;
}

/// 4th-order central difference of a scalar/tensor function of F in direction E_kl. (The
/// result is evaluated into a value: an Eigen expression would refer to dead temporaries.)
template <int D, class Fn>
auto fd4(Fn&& fn, const Tensor<D>& F, int k, int l, double h) {
  using Value = std::decay_t<decltype(fn(F))>;
  auto at = [&](double t) -> Value {
    Tensor<D> G = F;
    G(k, l) += t;
    return fn(G);
  };
  const Value a = at(2 * h), b = at(h), c = at(-h), d = at(-2 * h);
  return Value((-a + 8.0 * b - 8.0 * c + d) / (12.0 * h));
}

}  // namespace hstest
