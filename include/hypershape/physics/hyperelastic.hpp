#pragma once
/// Hand-written, fixed-size element loops for any hyperelastic kernel `K<D>` with
///   bool energy(F, W), bool stress(F, P), bool stress_tangent(F, P, A),
///   std::vector<double> constants(), static K<D> from_constants(const PetscScalar*)
/// (see tensor.hpp, neo_hookean.hpp). Total Lagrangian: the reference geometry is fixed, so everything
/// geometric comes precomputed from Space. A material file instantiates HyperelasticEffect with
/// its kernel; the PETSc pointwise functions of the generic path come from the same kernel.
///
/// A modulus field: W(x, F) = m(x) W(F) with a positive factor m(x) evaluated at every
/// quadrature point once per mesh (setup). It multiplies the quadrature weight, so a material
/// without a field assembles exactly the same numbers as before fields existed.
#include <Eigen/Dense>
#include <array>
#include <functional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "hypershape/core/error.hpp"
#include "hypershape/physics/effect.hpp"
#include "hypershape/physics/tensor.hpp"

namespace hypershape::physics {

namespace detail {

// The 2D loops below are written out by hand where Eigen's fixed-size products were out-of-line
// calls (F = I + ue^T G alone took 9% of a Random2D P2 run's CPU, `perf`), each summing in the
// order Eigen's vectorised product sums (tested bit for bit in unit.physics.assembly), so the
// data keep every bit. 3D keeps Eigen's products: there the factorisations are the cost.

/// Physical basis gradients G (NB x D) of cell c at quadrature point q.
template <int D, int NB>
[[gnu::always_inline]] inline void physical_gradients(const Space& s, PetscInt c, int q, Eigen::Matrix<double, NB, D>& G) {
  Eigen::Map<const Eigen::Matrix<double, NB, D, Eigen::RowMajor>> dref(s.ref_grad(q));
  Eigen::Map<const Eigen::Matrix<double, D, D, Eigen::RowMajor>> iJ(s.inv_jacobian(c));
  if constexpr (D == 2) {
    for (int j = 0; j < 2; ++j)
      for (int a = 0; a < NB; ++a) G(a, j) = dref(a, 0) * iJ(0, j) + dref(a, 1) * iJ(1, j);
  } else {
    G.noalias() = dref * iJ;  // dN/dx_j = sum_k dN/dxi_k dxi_k/dx_j
  }
}

/// F = I + ue^T G: F_ij = delta_ij + sum_a ue(a, i) G(a, j). In 2D P2 as Eigen sums six terms in
/// lanes of two (the even and the odd a, each lane's last two first, then the lanes' sum); P1's
/// three in turn.
template <int D, int NB>
[[gnu::always_inline]] inline Tensor<D> deformation_gradient(const Eigen::Matrix<double, NB, D>& ue,
                                                             const Eigen::Matrix<double, NB, D>& G) {
  if constexpr (D == 2 && (NB == 3 || NB == 6)) {
    Tensor<2> F;
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i) {
        double sum;
        if constexpr (NB == 6) {
          const double even = ue(0, i) * G(0, j) + (ue(2, i) * G(2, j) + ue(4, i) * G(4, j));
          const double odd = ue(1, i) * G(1, j) + (ue(3, i) * G(3, j) + ue(5, i) * G(5, j));
          sum = even + odd;
        } else {
          sum = ue(0, i) * G(0, j) + ue(1, i) * G(1, j) + ue(2, i) * G(2, j);
        }
        F(i, j) = (i == j ? 1.0 : 0.0) + sum;
      }
    return F;
  } else {
    return Tensor<D>::Identity() + ue.transpose() * G;
  }
}

/// re += w G P^T: re_ai += sum_J w G_aJ P_iJ (a quadrature point's part of the cell residual), with
/// w G_aJ formed first as Eigen forms it.
template <int D, int NB>
[[gnu::always_inline]] inline void add_point_residual(const Eigen::Matrix<double, NB, D>& G, const Tensor<D>& P, double w,
                                                      Eigen::Matrix<double, NB, D>& re) {
  if constexpr (D == 2) {
    for (int i = 0; i < 2; ++i)
      for (int a = 0; a < NB; ++a) re(a, i) += (w * G(a, 0)) * P(i, 0) + (w * G(a, 1)) * P(i, 1);
  } else {
    re.noalias() += w * (G * P.transpose());
  }
}

template <int D, int NB>
[[gnu::always_inline]] inline void gather(const Space& s, PetscInt c, const PetscScalar* u, Eigen::Matrix<double, NB, D>& ue) {
  const PetscInt* idx = s.local_dofs(c);
  for (int a = 0; a < NB; ++a)
    for (int i = 0; i < D; ++i) ue(a, i) = u[idx[a * D + i]];
}

template <int D>
Tensor<D> deformation_gradient(const PetscScalar u_x[]) {
  Tensor<D> F;
  for (int i = 0; i < D; ++i)
    for (int j = 0; j < D; ++j) F(i, j) = (i == j ? 1.0 : 0.0) + u_x[i * D + j];
  return F;
}

/// PETSc pointwise residual f1 = P(F) of kernel K (constants: K's constants()).
template <template <int> class K>
void f1_pointwise(PetscInt dim, PetscInt, PetscInt, const PetscInt[], const PetscInt[],
                  const PetscScalar[], const PetscScalar[], const PetscScalar u_x[],
                  const PetscInt[], const PetscInt[], const PetscScalar[], const PetscScalar[],
                  const PetscScalar[], PetscReal, const PetscReal[], PetscInt,
                  const PetscScalar c[], PetscScalar f1[]) {
  auto run = [&]<int D>() {
    Tensor<D> P = Tensor<D>::Zero();
    K<D>::from_constants(c).stress(deformation_gradient<D>(u_x), P);
    for (int i = 0; i < D; ++i)
      for (int j = 0; j < D; ++j) f1[i * D + j] = P(i, j);
  };
  if (dim == 2) run.template operator()<2>(); else run.template operator()<3>();
}

/// PETSc pointwise tangent g3 = dP/dF of kernel K.
template <template <int> class K>
void g3_pointwise(PetscInt dim, PetscInt, PetscInt, const PetscInt[], const PetscInt[],
                  const PetscScalar[], const PetscScalar[], const PetscScalar u_x[],
                  const PetscInt[], const PetscInt[], const PetscScalar[], const PetscScalar[],
                  const PetscScalar[], PetscReal, PetscReal, const PetscReal[], PetscInt,
                  const PetscScalar c[], PetscScalar g3[]) {
  auto run = [&]<int D>() {
    Tensor<D> P;
    Tangent<D> A = Tangent<D>::Zero();
    K<D>::from_constants(c).stress_tangent(deformation_gradient<D>(u_x), P, A);
    // PETSc layout: g3[((i * D + k) * D + J) * D + L] = dP_iJ / dF_kL.
    for (int i = 0; i < D; ++i)
      for (int k = 0; k < D; ++k)
        for (int J = 0; J < D; ++J)
          for (int L = 0; L < D; ++L) g3[((i * D + k) * D + J) * D + L] = A(i * D + J, k * D + L);
  };
  if (dim == 2) run.template operator()<2>(); else run.template operator()<3>();
}

/// W(F) and P(F) of kernel K at once: its energy_stress where it has one (sharing det F and
/// ln J), else energy then stress. The same numbers either way.
template <class K, class T>
bool energy_stress(const K& k, const T& F, double& W, T& P) {
  if constexpr (requires { k.energy_stress(F, W, P); }) return k.energy_stress(F, W, P);
  else return k.energy(F, W) && k.stress(F, P);
}

/// AG(iJ, b k) = sum_L A(iJ, kL) G(b, L): the point's tangent applied to each basis gradient.
template <int D, int NB, class AGMatrix>
[[gnu::always_inline]] inline void tangent_gradients(const Tangent<D>& A, const Eigen::Matrix<double, NB, D>& G, AGMatrix& AG) {
  if constexpr (D == 2) {
    for (int r = 0; r < D * D; ++r)
      for (int b = 0; b < NB; ++b)
        for (int k = 0; k < D; ++k) AG(r, b * D + k) = A(r, k * D) * G(b, 0) + A(r, k * D + 1) * G(b, 1);
  } else {
    for (int b = 0; b < NB; ++b)
      for (int k = 0; k < D; ++k) AG.col(b * D + k).noalias() = A.template middleCols<D>(k * D) * G.row(b).transpose();
  }
}

/// One quadrature point's part of a cell tangent: Ke(a i, :) += sum_J (w G(a, J)) AG(i J, :)
/// with AG(iJ, b k) = sum_L A(iJ, kL) G(b, L). In 2D along AG's contiguous rows (row-major), which
/// the compiler vectorises lane by lane: Eigen's numbers for the product of the 3D branch, faster.
template <int D, int NB, class AGMatrix>
[[gnu::always_inline]] inline void add_point_tangent(const Eigen::Matrix<double, NB, D>& G, const AGMatrix& AG, double w,
                                                     Eigen::Matrix<double, NB * D, NB * D, Eigen::RowMajor>& Ke) {
  constexpr int ND = NB * D;
  if constexpr (D == 2) {
    static_assert(AGMatrix::IsRowMajor);
    for (int a = 0; a < NB; ++a) {
      const double g0 = w * G(a, 0), g1 = w * G(a, 1);
      for (int i = 0; i < D; ++i) {
        double* ke = Ke.data() + (a * D + i) * ND;
        const double *r0 = AG.data() + (i * D) * ND, *r1 = r0 + ND;
        for (int col = 0; col < ND; ++col) ke[col] += g0 * r0[col] + g1 * r1[col];
      }
    }
  } else {
    for (int a = 0; a < NB; ++a)
      for (int i = 0; i < D; ++i) Ke.row(a * D + i).noalias() += w * (G.row(a) * AG.template middleRows<D>(i * D));
  }
}

/// Runs `op.operator()<D, NB>()` for the space's dimension D and nodes per cell NB.
template <class Op>
bool dispatch(const Space& s, Op&& op) {
  switch (s.dim() * 10 + s.degree()) {
    case 21: return op.template operator()<2, 3>();
    case 22: return op.template operator()<2, 6>();
    case 31: return op.template operator()<3, 4>();
    case 32: return op.template operator()<3, 10>();
  }
  return false;
}

}  // namespace detail

/// A stored-energy effect from a pointwise kernel family K<2>, K<3>, optionally times a
/// modulus field m(x) (`field`, empty for none).
template <template <int> class K>
class HyperelasticEffect : public Effect {
 public:
  HyperelasticEffect(std::string name, K<2> k2, K<3> k3, ScalarFunction field = {})
      : name_(std::move(name)), k2_(k2), k3_(k3), field_(std::move(field)) {}
  std::string name() const override { return name_; }
  bool has_energy() const override { return true; }

  /// Evaluates the modulus field at the quadrature points of the local cells. Not collective.
  void setup(const Space& s) override {
    factor_.clear();
    if (!field_) return;
    factor_.reserve(std::size_t(s.cell_end() - s.cell_begin()) * s.n_qp());
    for (PetscInt c = s.cell_begin(); c < s.cell_end(); ++c)
      for (int q = 0; q < s.n_qp(); ++q) {
        double x[3] = {0, 0, 0};
        s.map_point(c, q, x);
        factor_.push_back(field_(x));
      }
  }
  /// The modulus field's channel: m(x) in the first component (a scalar field).
  std::string channel() const override { return field_ ? "modulus" : ""; }
  int channel_components(int) const override { return 1; }
  void channel_value(const double* x, double* value) const override {
    value[0] = field_ ? field_(x) : 1.0;
  }
  bool has_field() const { return bool(field_); }

  void set_pointwise(PetscDS ds) const override {
    if (field_)
      throw std::logic_error(name_ + ": PETSc's pointwise path has no modulus field (cross-checks "
                                     "are for homogeneous materials)");
    const std::vector<double> k = k2_.constants();
    std::vector<PetscScalar> c(k.begin(), k.end());
    HS_PETSC(PetscDSSetConstants(ds, PetscInt(c.size()), c.data()));
    HS_PETSC(PetscDSSetResidual(ds, 0, nullptr, detail::f1_pointwise<K>));
    HS_PETSC(PetscDSSetJacobian(ds, 0, 0, nullptr, nullptr, nullptr, detail::g3_pointwise<K>));
  }

  bool add_energy(const Space& s, const PetscScalar* u, double& energy) const override {
    return detail::dispatch(s, [&]<int D, int NB>() {
      const auto& k = kernel<D>();
      Eigen::Matrix<double, NB, D> ue, G;
      for (PetscInt c : s.cells()) {
        detail::gather<D, NB>(s, c, u, ue);
        const double dj = s.det_jacobian(c);
        for (int q = 0; q < s.n_qp(); ++q) {
          detail::physical_gradients<D, NB>(s, c, q, G);
          const Tensor<D> F = detail::deformation_gradient<D, NB>(ue, G);
          double W;
          if (!k.energy(F, W)) return false;
          energy += weight(s, c, q, dj) * W;
        }
      }
      return true;
    });
  }

  bool add_residual(const Space& s, const PetscScalar* u, PetscScalar* r) const override {
    return detail::dispatch(s, [&]<int D, int NB>() {
      const auto& k = kernel<D>();
      Eigen::Matrix<double, NB, D> ue, G, re;
      Tensor<D> P;
      for (PetscInt c : s.cells()) {
        detail::gather<D, NB>(s, c, u, ue);
        const double dj = s.det_jacobian(c);
        re.setZero();
        for (int q = 0; q < s.n_qp(); ++q) {
          detail::physical_gradients<D, NB>(s, c, q, G);
          const Tensor<D> F = detail::deformation_gradient<D, NB>(ue, G);
          if (!k.stress(F, P)) return false;
          detail::add_point_residual<D, NB>(G, P, weight(s, c, q, dj), re);  // r_ai = sum_J P_iJ G_aJ
        }
        const PetscInt* idx = s.local_dofs(c);
        for (int a = 0; a < NB; ++a)
          for (int i = 0; i < D; ++i) r[idx[a * D + i]] += re(a, i);
      }
      return true;
    });
  }

  // add_residual's loop with the energy in it. Kept as its own loop on purpose: one template for
  // both (add_forces<bool>) gave the same bits but cost 1.1-1.8% of a Random2D P2 run, 6.8% with
  // the energy summed in a local (whole processes timed in alternating pairs, 3 each, 2026-11-27); this is the hot path.
  bool add_energy_residual(const Space& s, const PetscScalar* u, double& energy, PetscScalar* r) const override {
    return detail::dispatch(s, [&]<int D, int NB>() {
      const auto& k = kernel<D>();
      Eigen::Matrix<double, NB, D> ue, G, re;
      Tensor<D> P;
      for (PetscInt c : s.cells()) {
        detail::gather<D, NB>(s, c, u, ue);
        const double dj = s.det_jacobian(c);
        re.setZero();
        for (int q = 0; q < s.n_qp(); ++q) {
          detail::physical_gradients<D, NB>(s, c, q, G);
          const Tensor<D> F = detail::deformation_gradient<D, NB>(ue, G);
          double W;
          if (!detail::energy_stress(k, F, W, P)) return false;
          const double w = weight(s, c, q, dj);
          energy += w * W;
          detail::add_point_residual<D, NB>(G, P, w, re);
        }
        const PetscInt* idx = s.local_dofs(c);
        for (int a = 0; a < NB; ++a)
          for (int i = 0; i < D; ++i) r[idx[a * D + i]] += re(a, i);
      }
      return true;
    });
  }

  bool add_jacobian(const Space& s, const PetscScalar* u, Mat J) const override {
    return detail::dispatch(s, [&]<int D, int NB>() {
      constexpr int ND = NB * D;
      const auto& k = kernel<D>();
      Eigen::Matrix<double, NB, D> ue, G;
      Eigen::Matrix<double, ND, ND, Eigen::RowMajor> Ke;
      // AG(iJ, b k) = sum_L A(iJ, kL) G(b, L): row-major in 2D (add_point_tangent); column-major in
      // 3D, where Eigen sums the three terms of its products in an order that depends on the layout.
      std::conditional_t<D == 2, Eigen::Matrix<double, D * D, ND, Eigen::RowMajor>, Eigen::Matrix<double, D * D, ND>> AG;
      Tensor<D> P;
      Tangent<D> A;
      const CellMatrixAdder adder(s, J);
      for (PetscInt c : s.cells()) {
        detail::gather<D, NB>(s, c, u, ue);
        const double dj = s.det_jacobian(c);
        Ke.setZero();
        for (int q = 0; q < s.n_qp(); ++q) {
          detail::physical_gradients<D, NB>(s, c, q, G);
          const Tensor<D> F = detail::deformation_gradient<D, NB>(ue, G);
          if (!k.stress_tangent(F, P, A)) return false;
          const double w = weight(s, c, q, dj);
          detail::tangent_gradients<D, NB>(A, G, AG);
          detail::add_point_tangent<D, NB>(G, AG, w, Ke);
        }
        adder.add(c, Ke.data());
      }
      return true;
    });
  }

 private:
  template <int D>
  const K<D>& kernel() const {
    if constexpr (D == 2) return k2_; else return k3_;
  }
  /// Quadrature weight times det J, times the modulus field there if there is one.
  double weight(const Space& s, PetscInt c, int q, double dj) const {
    const double w = s.qweight(q) * dj;
    return factor_.empty() ? w : w * factor_[std::size_t(c - s.cell_begin()) * s.n_qp() + q];
  }
  std::string name_;
  K<2> k2_;
  K<3> k3_;
  ScalarFunction field_;
  std::vector<double> factor_;  ///< m(x) per local cell and quadrature point
};

}  // namespace hypershape::physics
