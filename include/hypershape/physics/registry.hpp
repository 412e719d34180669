#pragma once
/// Built-in effects: one registration function per effect file, called once by registry.cpp.
#include "hypershape/physics/effect.hpp"

namespace hypershape::physics {

void register_neo_hookean();
void register_dirichlet_patch();
void register_gaussian_traction();
void register_body_force();

/// Direct constructors of the built-in effects (tests, benchmarks, programmatic scenes).
EffectPtr make_neo_hookean(double E, double nu);
EffectPtr make_dirichlet_patch(const std::vector<double>& center, double radius);
/// t(x) = g phi(x - p_N) / I_N, phi(y) = exp(-|y|^2 / (2 gamma^2)), I_N = int_{Gamma_N} phi;
/// `direction` is normalised. The load factor (alpha) scales it.
EffectPtr make_gaussian_traction(const std::vector<double>& center,
                                 const std::vector<double>& direction, double gamma);

}  // namespace hypershape::physics
