/// The seed's Neo-Hookean with its volumetric energy on each cell's mean dilatation
/// (`neo_hookean: {..., dilatation: mean}`), a locking-free option for nearly incompressible
/// bodies on P2 meshes. The energy of cell e is
///   int_e mu/2 (I1 - d - 2 ln J) dX + V_e lambda/2 (ln theta_e)^2,   theta_e = v_e / V_e,
/// v_e = int_e J dX the cell's deformed volume, V_e its reference volume: the mean-dilatation
/// (Nagtegaal, Parks and Rice 1974; Simo, Taylor and Pister 1985) or P2/P0 element, a pure
/// displacement method with a symmetric tangent (the path follower and its inertia-based
/// stability check apply unchanged). Where theta_e = J (homogeneous deformations; P1 cells, whose
/// J is constant) it is the pointwise Neo-Hookean exactly. With
///   g = dv_e/du = sum_q w_q J (G F^-1),   H = d^2 v_e / du^2 (J (B_ai B_bk - B_ak B_bi), B = G F^-1),
///   U(theta) = lambda/2 ln^2 theta,  U' = lambda ln theta / theta,  U'' = lambda (1 - ln theta) / theta^2,
/// the cell's residual is U' g and its tangent U''/V_e g g^T + U' H (+ the mu part's, pointwise).
/// A modulus field m(x) scales mu pointwise and lambda by its cell mean.
///
/// pointwise_share b (key `pointwise_share`, default 0) puts the share b of lambda back on the
/// pointwise dilatation: V_e (1 - b) lambda/2 (ln theta_e)^2 + int_e b lambda/2 (ln J)^2 dX. With
/// b = 0, a traction narrower than a cell (gamma 0.1 on the random3d preset's 0.25 cells)
/// crushes the part of the cell under it -- only the cell's mean volume is held -- and the label
/// inverts between the quadrature points (docs/ACCURACY.md, "Labels that invert inside a cell").
#include <cmath>
#include <stdexcept>

#include "hypershape/physics/hyperelastic.hpp"
#include "hypershape/physics/neo_hookean.hpp"
#include "hypershape/physics/registry.hpp"

namespace hypershape::physics {

namespace {

class MeanDilatationNeoHookean : public Effect {
 public:
  /// lambda: the bulk modulus on the cell means; lambda_pointwise: the one at every point.
  MeanDilatationNeoHookean(double mu, double lambda, ScalarFunction field, double lambda_pointwise)
      : shear_("neo_hookean", NeoHookean<2>{mu, lambda_pointwise}, NeoHookean<3>{mu, lambda_pointwise}, field),
        lambda_(lambda),
        field_(std::move(field)) {}

  std::string name() const override { return "neo_hookean"; }
  bool has_energy() const override { return true; }
  std::string channel() const override { return shear_.channel(); }
  int channel_components(int dim) const override { return shear_.channel_components(dim); }
  void channel_value(const double* x, double* value) const override { shear_.channel_value(x, value); }
  void set_pointwise(PetscDS) const override {
    throw std::logic_error("neo_hookean with dilatation: mean has no PETSc pointwise form (a cell-mean energy)");
  }

  /// The cells' bulk moduli lambda times the cell mean of the modulus field.
  void setup(const Space& s) override {
    shear_.setup(s);
    lambda_cell_.assign(std::size_t(s.cell_end() - s.cell_begin()), lambda_);
    if (!field_) return;
    for (PetscInt c = s.cell_begin(); c < s.cell_end(); ++c) {
      double m = 0, w = 0;
      for (int q = 0; q < s.n_qp(); ++q) {
        double x[3] = {0, 0, 0};
        s.map_point(c, q, x);
        m += s.qweight(q) * field_(x);
        w += s.qweight(q);
      }
      lambda_cell_[std::size_t(c - s.cell_begin())] *= m / w;
    }
  }

  bool add_energy(const Space& s, const PetscScalar* u, double& energy) const override {
    if (!shear_.add_energy(s, u, energy)) return false;
    return for_cells<false>(s, u, [&](PetscInt c, const auto& cell) { add_volumetric_energy(s, c, cell, energy); });
  }

  bool add_residual(const Space& s, const PetscScalar* u, PetscScalar* r) const override {
    if (!shear_.add_residual(s, u, r)) return false;
    return for_cells<false>(s, u, [&](PetscInt c, const auto& cell) { add_volumetric_residual(s, c, cell, r); });
  }

  bool add_energy_residual(const Space& s, const PetscScalar* u, double& energy, PetscScalar* r) const override {
    if (!shear_.add_energy_residual(s, u, energy, r)) return false;
    return for_cells<false>(s, u, [&](PetscInt c, const auto& cell) {
      add_volumetric_energy(s, c, cell, energy);
      add_volumetric_residual(s, c, cell, r);
    });
  }

  bool add_jacobian(const Space& s, const PetscScalar* u, Mat J) const override {
    if (!shear_.add_jacobian(s, u, J)) return false;
    const CellMatrixAdder adder(s, J);
    return for_cells<true>(s, u, [&](PetscInt c, auto& cell) {
      const double theta = cell.theta(), ln = std::log(theta), lam = lambda(s, c);
      const double dU = lam * ln / theta, d2U = lam * (1.0 - ln) / (theta * theta);
      Eigen::Map<const Eigen::Matrix<double, 1, decltype(cell.H)::RowsAtCompileTime>> g(cell.g.data());
      cell.H *= dU;
      cell.H.noalias() += (d2U / cell.V) * g.transpose() * g;
      adder.add(c, cell.H.data());
    });
  }

 private:
  /// One cell's volumes, dv/du (g, NB x D, row-major: node-major like the dofs) and, if asked,
  /// d^2v/du^2 (H, ND x ND).
  template <int D, int NB>
  struct Cell {
    double V = 0, v = 0;
    Eigen::Matrix<double, NB, D, Eigen::RowMajor> g;
    Eigen::Matrix<double, NB * D, NB * D, Eigen::RowMajor> H;
    double theta() const { return v / V; }
  };

  /// Cell c's V_e lambda/2 (ln theta_e)^2 into `energy`.
  template <class C>
  void add_volumetric_energy(const Space& s, PetscInt c, const C& cell, double& energy) const {
    const double ln = std::log(cell.theta());
    energy += 0.5 * lambda(s, c) * cell.V * ln * ln;
  }
  /// Cell c's U'(theta_e) g into the local residual array `r`.
  template <class C>
  void add_volumetric_residual(const Space& s, PetscInt c, const C& cell, PetscScalar* r) const {
    const double theta = cell.theta();
    const double dU = lambda(s, c) * std::log(theta) / theta;
    const PetscInt* idx = s.local_dofs(c);
    for (int a = 0; a < cell.g.rows(); ++a)
      for (int i = 0; i < cell.g.cols(); ++i) r[idx[a * cell.g.cols() + i]] += dU * cell.g(a, i);
  }

  /// Runs op(c, cell) for each local cell with v, V, g (and H when `hessian`); false if some
  /// quadrature point has det F <= 0.
  template <bool hessian, class Op>
  bool for_cells(const Space& s, const PetscScalar* u, Op&& op) const {
    return detail::dispatch(s, [&]<int D, int NB>() {
      Eigen::Matrix<double, NB, D> ue, G;
      Cell<D, NB> cell;
      for (PetscInt c : s.cells()) {
        detail::gather<D, NB>(s, c, u, ue);
        const double dj = s.det_jacobian(c);
        cell.V = cell.v = 0;
        cell.g.setZero();
        if constexpr (hessian) cell.H.setZero();
        for (int q = 0; q < s.n_qp(); ++q) {
          detail::physical_gradients<D, NB>(s, c, q, G);
          const Tensor<D> F = detail::deformation_gradient<D, NB>(ue, G);
          const double Jq = F.determinant();
          if (!(Jq > 0)) return false;
          const double w = s.qweight(q) * dj;
          const Eigen::Matrix<double, NB, D> B = G * F.inverse();  // dJ/du_ai = J B_ai
          cell.V += w;
          cell.v += w * Jq;
          cell.g.noalias() += (w * Jq) * B;
          if constexpr (hessian) add_volume_hessian<D, NB>(w * Jq, B, cell.H);
        }
        op(c, cell);
      }
      return true;
    });
  }

  /// H(ai, bk) += wJ (B_ai B_bk - B_ak B_bi).
  template <int D, int NB>
  static void add_volume_hessian(double wJ, const Eigen::Matrix<double, NB, D>& B,
                                 Eigen::Matrix<double, NB * D, NB * D, Eigen::RowMajor>& H) {
    for (int a = 0; a < NB; ++a)
      for (int i = 0; i < D; ++i)
        for (int b = 0; b < NB; ++b)
          for (int k = 0; k < D; ++k) H(a * D + i, b * D + k) += wJ * (B(a, i) * B(b, k) - B(a, k) * B(b, i));
  }

  double lambda(const Space& s, PetscInt c) const { return lambda_cell_[std::size_t(c - s.cell_begin())]; }

  HyperelasticEffect<NeoHookean> shear_;  ///< mu/2 (I1 - d - 2 ln J), pointwise
  double lambda_;
  ScalarFunction field_;
  std::vector<double> lambda_cell_;  ///< per local cell
};

}  // namespace

EffectPtr make_neo_hookean_mean_dilatation(double E, double nu, ScalarFunction field, double pointwise_share) {
  const Lame l = Lame::from_young_poisson(E, nu);
  return std::make_unique<MeanDilatationNeoHookean>(l.mu, (1 - pointwise_share) * l.lambda, std::move(field),
                                                    pointwise_share * l.lambda);
}

}  // namespace hypershape::physics
