/// Effect "neo_hookean": the seed paper's compressible Neo-Hookean material (appendix A).
/// Keys: E (Young's modulus, > 0), nu (Poisson's ratio, in (-1, 0.5)).
#include "hypershape/physics/neo_hookean.hpp"

#include "hypershape/core/error.hpp"
#include "hypershape/physics/hyperelastic.hpp"
#include "hypershape/physics/registry.hpp"

namespace hypershape::physics {

namespace {

template <int D>
Tensor<D> deformation_gradient(const PetscScalar u_x[]) {
  Tensor<D> F;
  for (int i = 0; i < D; ++i)
    for (int j = 0; j < D; ++j) F(i, j) = (i == j ? 1.0 : 0.0) + u_x[i * D + j];
  return F;
}

// PETSc pointwise functions (constants: mu, lambda).
void f1_pointwise(PetscInt dim, PetscInt, PetscInt, const PetscInt[], const PetscInt[],
                  const PetscScalar[], const PetscScalar[], const PetscScalar u_x[],
                  const PetscInt[], const PetscInt[], const PetscScalar[], const PetscScalar[],
                  const PetscScalar[], PetscReal, const PetscReal[], PetscInt,
                  const PetscScalar c[], PetscScalar f1[]) {
  auto run = [&]<int D>() {
    Tensor<D> P = Tensor<D>::Zero();
    NeoHookean<D>{c[0], c[1]}.stress(deformation_gradient<D>(u_x), P);
    for (int i = 0; i < D; ++i)
      for (int j = 0; j < D; ++j) f1[i * D + j] = P(i, j);
  };
  if (dim == 2) run.template operator()<2>(); else run.template operator()<3>();
}

void g3_pointwise(PetscInt dim, PetscInt, PetscInt, const PetscInt[], const PetscInt[],
                  const PetscScalar[], const PetscScalar[], const PetscScalar u_x[],
                  const PetscInt[], const PetscInt[], const PetscScalar[], const PetscScalar[],
                  const PetscScalar[], PetscReal, PetscReal, const PetscReal[], PetscInt,
                  const PetscScalar c[], PetscScalar g3[]) {
  auto run = [&]<int D>() {
    Tensor<D> P;
    Tangent<D> A = Tangent<D>::Zero();
    NeoHookean<D>{c[0], c[1]}.stress_tangent(deformation_gradient<D>(u_x), P, A);
    // PETSc layout: g3[((i * D + k) * D + J) * D + L] = dP_iJ / dF_kL.
    for (int i = 0; i < D; ++i)
      for (int k = 0; k < D; ++k)
        for (int J = 0; J < D; ++J)
          for (int L = 0; L < D; ++L) g3[((i * D + k) * D + J) * D + L] = A(i * D + J, k * D + L);
  };
  if (dim == 2) run.template operator()<2>(); else run.template operator()<3>();
}

class NeoHookeanEffect : public HyperelasticEffect<NeoHookean> {
 public:
  explicit NeoHookeanEffect(Lame l)
      : HyperelasticEffect<NeoHookean>("neo_hookean", {l.mu, l.lambda}, {l.mu, l.lambda}), lame_(l) {}
  void set_pointwise(PetscDS ds) const override {
    const PetscScalar c[2] = {lame_.mu, lame_.lambda};
    HS_PETSC(PetscDSSetConstants(ds, 2, const_cast<PetscScalar*>(c)));
    HS_PETSC(PetscDSSetResidual(ds, 0, nullptr, f1_pointwise));
    HS_PETSC(PetscDSSetJacobian(ds, 0, 0, nullptr, nullptr, nullptr, g3_pointwise));
  }

 private:
  Lame lame_;
};

}  // namespace

EffectPtr make_neo_hookean(double E, double nu) {
  return std::make_unique<NeoHookeanEffect>(Lame::from_young_poisson(E, nu));
}

void register_neo_hookean() {
  register_effect(
      "neo_hookean",
      [](const core::Params& p, int) {
        const double E = p.number_in("E", 0.0, 1e300, true);
        const double nu = p.number_in("nu", -1.0, 0.5, true, true);
        return make_neo_hookean(E, nu);
      },
      "compressible Neo-Hookean material (seed, appendix A); keys: E > 0, nu in (-1, 0.5)");
}

}  // namespace hypershape::physics
