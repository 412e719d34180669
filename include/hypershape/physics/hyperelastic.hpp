#pragma once
/// Hand-written, fixed-size element loops for any hyperelastic kernel `K<D>` with
///   bool energy(F, W), bool stress(F, P), bool stress_tangent(F, P, A)
/// (see neo_hookean.hpp). Total Lagrangian: the reference geometry is fixed, so everything
/// geometric comes precomputed from Space. A material file instantiates HyperelasticEffect with
/// its kernel and adds PETSc pointwise functions for the generic path.
#include <Eigen/Dense>
#include <array>
#include <string>

#include "hypershape/physics/effect.hpp"
#include "hypershape/physics/neo_hookean.hpp"

namespace hypershape::physics {

namespace detail {

/// Physical basis gradients G (NB x D) of cell c at quadrature point q.
template <int D, int NB>
inline void physical_gradients(const Space& s, PetscInt c, int q, Eigen::Matrix<double, NB, D>& G) {
  Eigen::Map<const Eigen::Matrix<double, NB, D, Eigen::RowMajor>> dref(s.ref_grad(q));
  Eigen::Map<const Eigen::Matrix<double, D, D, Eigen::RowMajor>> iJ(s.inv_jacobian(c));
  G.noalias() = dref * iJ;  // dN/dx_j = sum_k dN/dxi_k dxi_k/dx_j
}

template <int D, int NB>
inline void gather(const Space& s, PetscInt c, const PetscScalar* u, Eigen::Matrix<double, NB, D>& ue) {
  const PetscInt* idx = s.local_dofs(c);
  for (int a = 0; a < NB; ++a)
    for (int i = 0; i < D; ++i) ue(a, i) = u[idx[a * D + i]];
}

/// Loops over the local cells with kernel `K<D>` for the (D, NB) given at run time.
template <template <int> class K, class Op>
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

/// A stored-energy effect from a pointwise kernel family K<2>, K<3> built from parameters P.
template <template <int> class K>
class HyperelasticEffect : public Effect {
 public:
  HyperelasticEffect(std::string name, K<2> k2, K<3> k3) : name_(std::move(name)), k2_(k2), k3_(k3) {}
  std::string name() const override { return name_; }
  bool has_energy() const override { return true; }

  bool add_energy(const Space& s, const PetscScalar* u, double& energy) const override {
    return detail::dispatch<K>(s, [&]<int D, int NB>() {
      const auto& k = kernel<D>();
      Eigen::Matrix<double, NB, D> ue, G;
      for (PetscInt c = s.cell_begin(); c < s.cell_end(); ++c) {
        detail::gather<D, NB>(s, c, u, ue);
        const double dj = s.det_jacobian(c);
        for (int q = 0; q < s.n_qp(); ++q) {
          detail::physical_gradients<D, NB>(s, c, q, G);
          const Tensor<D> F = Tensor<D>::Identity() + ue.transpose() * G;
          double W;
          if (!k.energy(F, W)) return false;
          energy += s.qweight(q) * dj * W;
        }
      }
      return true;
    });
  }

  bool add_residual(const Space& s, const PetscScalar* u, PetscScalar* r) const override {
    return detail::dispatch<K>(s, [&]<int D, int NB>() {
      const auto& k = kernel<D>();
      Eigen::Matrix<double, NB, D> ue, G, re;
      Tensor<D> P;
      for (PetscInt c = s.cell_begin(); c < s.cell_end(); ++c) {
        detail::gather<D, NB>(s, c, u, ue);
        const double dj = s.det_jacobian(c);
        re.setZero();
        for (int q = 0; q < s.n_qp(); ++q) {
          detail::physical_gradients<D, NB>(s, c, q, G);
          const Tensor<D> F = Tensor<D>::Identity() + ue.transpose() * G;
          if (!k.stress(F, P)) return false;
          re.noalias() += (s.qweight(q) * dj) * (G * P.transpose());  // r_ai = sum_J P_iJ G_aJ
        }
        const PetscInt* idx = s.local_dofs(c);
        for (int a = 0; a < NB; ++a)
          for (int i = 0; i < D; ++i) r[idx[a * D + i]] += re(a, i);
      }
      return true;
    });
  }

  bool add_jacobian(const Space& s, const PetscScalar* u, Mat J) const override {
    return detail::dispatch<K>(s, [&]<int D, int NB>() {
      constexpr int ND = NB * D;
      const auto& k = kernel<D>();
      Eigen::Matrix<double, NB, D> ue, G;
      Eigen::Matrix<double, ND, ND, Eigen::RowMajor> Ke;
      Eigen::Matrix<double, D * D, ND> AG;  // (iJ, b k) = sum_L A(iJ, kL) G(b, L)
      Tensor<D> P;
      Tangent<D> A;
      const CellMatrixAdder adder(s, J);
      for (PetscInt c = s.cell_begin(); c < s.cell_end(); ++c) {
        detail::gather<D, NB>(s, c, u, ue);
        const double dj = s.det_jacobian(c);
        Ke.setZero();
        for (int q = 0; q < s.n_qp(); ++q) {
          detail::physical_gradients<D, NB>(s, c, q, G);
          const Tensor<D> F = Tensor<D>::Identity() + ue.transpose() * G;
          if (!k.stress_tangent(F, P, A)) return false;
          const double w = s.qweight(q) * dj;
          for (int b = 0; b < NB; ++b)
            for (int kk = 0; kk < D; ++kk)
              AG.col(b * D + kk).noalias() = A.template middleCols<D>(kk * D) * G.row(b).transpose();
          for (int a = 0; a < NB; ++a)
            for (int i = 0; i < D; ++i)
              Ke.row(a * D + i).noalias() += w * (G.row(a) * AG.template middleRows<D>(i * D));
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
  std::string name_;
  K<2> k2_;
  K<3> k3_;
};

}  // namespace hypershape::physics
