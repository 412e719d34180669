#pragma once
/// The seed paper's traction (section 3.2): t(x) = alpha g phi(x - p_N) / I_N with
/// phi(y) = exp(-|y|^2 / (2 gamma^2)) and I_N = int_{Gamma_N} phi dS (facet rule). alpha is the
/// problem's load factor. The factory moves p_N and g per load case (set(), then
/// Problem::reassemble_load()), keeping the mesh, matrix and factorisation of the shape.
#include <array>
#include <vector>

#include "hypershape/physics/effect.hpp"

namespace hypershape::physics {

class GaussianTraction : public Effect {
 public:
  /// `direction` is normalised here (must be non-zero).
  GaussianTraction(std::vector<double> center, std::vector<double> direction, double gamma);
  std::string name() const override { return "gaussian_traction"; }
  /// Computes I_N on the space's Neumann facets (collective).
  void setup(const Space& space) override;
  bool has_load() const override { return true; }
  void add_load(const Space& space, PetscScalar* f) const override;
  std::string channel() const override { return "traction"; }
  bool channel_on_boundary() const override { return true; }
  void channel_value(const double* x, double* t) const override { value(x, t); }

  /// Moves the traction; call setup() again (Problem::reassemble_load does) before use.
  void set(std::vector<double> center, std::vector<double> direction);
  /// t(x) for alpha = 1 (valid after setup): `dim` components.
  void value(const double* x, double* t) const;
  double normaliser() const { return normaliser_; }
  const std::vector<double>& center() const { return center_; }
  const std::vector<double>& direction() const { return g_; }
  double gamma() const { return gamma_; }

 private:
  double phi(const double* x) const;
  std::vector<double> center_, g_;
  double gamma_;
  double normaliser_ = 0;
  int dim_ = 0;
};

}  // namespace hypershape::physics
