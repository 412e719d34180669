#pragma once
/// Built-in effects: one registration function per effect file, called once by registry.cpp.
#include "hypershape/physics/effect.hpp"
#include "hypershape/physics/region.hpp"

namespace hypershape::physics {

void register_neo_hookean();
void register_dirichlet_patch();
void register_gaussian_traction();
void register_body_force();
void register_saint_venant_kirchhoff();
void register_mooney_rivlin();
void register_linear_elastic();
void register_pressure();
void register_uniform_traction();
void register_dirichlet_region();
void register_spring();

/// Direct constructors of the built-in effects (tests, benchmarks, programmatic scenes).
/// Materials; `field` (optional) is a modulus factor m(x) > 0: W(x, F) = m(x) W(F).
EffectPtr make_neo_hookean(double E, double nu, ScalarFunction field = {});
/// The same material with its volumetric energy on each cell's mean dilatation (dilatation: mean).
/// pointwise_share in [0, 1): the share of the bulk modulus kept on the pointwise dilatation.
EffectPtr make_neo_hookean_mean_dilatation(double E, double nu, ScalarFunction field = {}, double pointwise_share = 0);
EffectPtr make_saint_venant_kirchhoff(double E, double nu, ScalarFunction field = {});
/// C1, C2 >= 0 with C1 + C2 > 0, kappa > 0 (see mooney_rivlin.hpp).
EffectPtr make_mooney_rivlin(double C1, double C2, double kappa, ScalarFunction field = {});
EffectPtr make_linear_elastic(double E, double nu, ScalarFunction field = {});
/// Dead pressure p on the region's Neumann facets: t = -p N (outward reference normal N).
EffectPtr make_pressure(double p, const Region& region, int dim);
/// Follower pressure p on the region's Neumann facets: t = -p J F^-T N, the pressure on the deformed
/// surface (Nanson). Not conservative in general: its tangent is not symmetric.
EffectPtr make_follower_pressure(double p, const Region& region, int dim);
/// Uniform dead traction t (dim components) on the region's Neumann facets.
EffectPtr make_uniform_traction(const std::vector<double>& t, const Region& region);
/// Elastic foundation on the region's Neumann facets: energy 1/2 int k_n (u.N)^2 + k_t |u - (u.N)N|^2 dS_0
/// (stiffnesses per unit reference area, >= 0).
EffectPtr make_spring(double normal_stiffness, double tangential_stiffness, const Region& region);
EffectPtr make_dirichlet_patch(const std::vector<double>& center, double radius);
/// t(x) = g phi(x - p_N) / I_N, phi(y) = exp(-|y|^2 / (2 gamma^2)), I_N = int_{Gamma_N} phi;
/// `direction` is normalised. The load factor (alpha) scales it.
EffectPtr make_gaussian_traction(const std::vector<double>& center,
                                 const std::vector<double>& direction, double gamma);

}  // namespace hypershape::physics
