#pragma once
/// Saint Venant-Kirchhoff: W = lambda/2 (tr E)^2 + mu tr(E^2), E = (C - I)/2, i.e. linear
/// elasticity in the Green-Lagrange strain (S = lambda tr E I + 2 mu E, P = F S). In the
/// invariants of C (tr E = (I1 - 3)/2, tr E^2 = (I1^2 - 2 I2 - 2 I1 + 3)/4):
///   W = lambda/8 (I1 - 3)^2 + mu/4 (I1^2 - 2 I2 - 2 I1 + 3),
/// plane strain in 2D (C_33 = 1). Known to soften without bound in compression (it admits
/// J -> 0 at finite energy); the kernel refuses J <= 0 like every material here.
#include <vector>

#include "hypershape/physics/invariant_material.hpp"

namespace hypershape::physics {

struct SaintVenantKirchhoffModel {
  double mu = 0, lambda = 0;
  bool evaluate(double I1, double I2, double, InvariantDerivatives& w) const {
    w.W = lambda / 8 * (I1 - 3) * (I1 - 3) + mu / 4 * (I1 * I1 - 2 * I2 - 2 * I1 + 3);
    w.d[0] = lambda / 4 * (I1 - 3) + mu / 2 * (I1 - 1);
    w.d[1] = -mu / 2;
    w.dd[0][0] = lambda / 4 + mu / 2;
    return true;
  }
};

template <int D>
struct SaintVenantKirchhoff : InvariantKernel<SaintVenantKirchhoffModel, D> {
  std::vector<double> constants() const { return {this->model.mu, this->model.lambda}; }
  static SaintVenantKirchhoff from_constants(const double* c) { return {{{c[0], c[1]}}}; }
};

}  // namespace hypershape::physics
