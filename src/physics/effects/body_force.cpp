/// Dead body force per unit reference volume. Effect "body_force"; key: value (a vector).
#include "hypershape/physics/registry.hpp"

namespace hypershape::physics {

namespace {

class BodyForce : public Effect {
 public:
  explicit BodyForce(VectorFunction b) : b_(std::move(b)) {}
  std::string name() const override { return "body_force"; }
  bool has_load() const override { return true; }
  std::string channel() const override { return "body_force"; }
  void channel_value(const double* x, double* b) const override { b_(x, b); }
  void add_load(const Space& s, PetscScalar* f) const override {
    const int dim = s.dim(), nb = s.n_nodes();
    for (PetscInt c = s.cell_begin(); c < s.cell_end(); ++c) {
      const PetscInt* idx = s.local_dofs(c);
      for (int q = 0; q < s.n_qp(); ++q) {
        double x[3] = {0, 0, 0}, b[3] = {0, 0, 0};
        s.map_point(c, q, x);
        b_(x, b);
        const double w = s.qweight(q) * s.det_jacobian(c);
        for (int a = 0; a < nb; ++a)
          for (int i = 0; i < dim; ++i) f[idx[a * dim + i]] += w * s.basis(q, a) * b[i];
      }
    }
  }

 private:
  VectorFunction b_;
};

}  // namespace

EffectPtr make_body_force(VectorFunction force, int) { return std::make_unique<BodyForce>(std::move(force)); }

void register_body_force() {
  register_effect(
      "body_force",
      [](const core::Params& p, int dim) {
        auto v = p.vector("value", std::size_t(dim));
        return make_body_force([v, dim](const double*, double* b) {
          for (int i = 0; i < dim; ++i) b[i] = v[i];
        });
      },
      "uniform dead body force per unit reference volume; key: value (a vector); scale: alpha "
      "(default) | fixed");
}

}  // namespace hypershape::physics
