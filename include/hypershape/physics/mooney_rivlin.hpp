#pragma once
/// Compressible Mooney-Rivlin with the isochoric/volumetric split (Holzapfel, Nonlinear Solid
/// Mechanics, 2000, sections 6.4-6.5; the Abaqus "Mooney-Rivlin" form with D1 = 2 / kappa):
///   W = C1 (Ib1 - 3) + C2 (Ib2 - 3) + kappa/2 (J - 1)^2,  Ib1 = J^(-2/3) I1, Ib2 = J^(-4/3) I2,
/// with the invariants of the 3D C (plane strain in 2D: C_33 = 1, J = det F). Linearised at
/// F = I it is isotropic linear elasticity with shear modulus mu = 2 (C1 + C2) and bulk modulus
/// kappa (lambda = kappa - 2 mu / 3). C2 = 0 is a (differently compressible) Neo-Hookean.
#include <cmath>
#include <vector>

#include "hypershape/physics/invariant_material.hpp"

namespace hypershape::physics {

struct MooneyRivlinModel {
  double C1 = 0, C2 = 0, kappa = 0;
  bool evaluate(double I1, double I2, double J, InvariantDerivatives& w) const {
    const double j23 = std::pow(J, -2.0 / 3.0), j43 = j23 * j23;  // J^(-2/3), J^(-4/3)
    w.W = C1 * (j23 * I1 - 3) + C2 * (j43 * I2 - 3) + kappa / 2 * (J - 1) * (J - 1);
    w.d[0] = C1 * j23;
    w.d[1] = C2 * j43;
    w.d[2] = -2.0 / 3.0 * C1 * j23 * I1 / J - 4.0 / 3.0 * C2 * j43 * I2 / J + kappa * (J - 1);
    w.dd[0][2] = w.dd[2][0] = -2.0 / 3.0 * C1 * j23 / J;
    w.dd[1][2] = w.dd[2][1] = -4.0 / 3.0 * C2 * j43 / J;
    w.dd[2][2] = 10.0 / 9.0 * C1 * j23 * I1 / (J * J) + 28.0 / 9.0 * C2 * j43 * I2 / (J * J) + kappa;
    return std::isfinite(w.W);
  }
};

template <int D>
struct MooneyRivlin : InvariantKernel<MooneyRivlinModel, D> {
  std::vector<double> constants() const { return {this->model.C1, this->model.C2, this->model.kappa}; }
  static MooneyRivlin from_constants(const double* c) { return {{{c[0], c[1], c[2]}}}; }
};

}  // namespace hypershape::physics
