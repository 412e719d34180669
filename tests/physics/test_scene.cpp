/// The one problem builder (physics::build_problem) and what a scene may say: draws, lists,
/// scale: fixed. A fixed load enters the residual and the energy unscaled, a scaled one times
/// the load factor, and the residual stays the gradient of the energy.
#include <catch2/catch.hpp>
#include <cmath>

#include "hypershape/core/input_error.hpp"
#include "hypershape/physics/scene.hpp"
#include "support/helpers.hpp"

using namespace hypershape;

namespace {

physics::EffectSpec effect(const std::string& name, std::map<std::string, physics::ParamValue> p,
                           bool scaled = true) {
  return {name, name, "effects." + name, std::move(p), scaled, !scaled, {}, 0};
}

/// The clamped disk with a Gaussian traction (scaled) and gravity, scaled or fixed.
physics::SceneSpec disk_scene(bool gravity_fixed) {
  physics::SceneSpec s;
  s.source = "<test>";
  s.effects = {effect("neo_hookean", {{"E", 500.0}, {"nu", 0.3}}),
               effect("dirichlet_patch", {{"center", std::vector<double>{1.0, 0.0}}, {"radius", 0.5}}),
               effect("gaussian_traction", {{"center", std::vector<double>{-1.0, 0.0}},
                                            {"direction", std::vector<double>{0.0, 1.0}}, {"gamma", 0.2}}),
               effect("body_force", {{"value", std::vector<double>{0.0, -3.0}}}, !gravity_fixed)};
  return s;
}

std::unique_ptr<physics::Problem> build(const physics::SceneSpec& s, const mesh::MeshData& m) {
  const auto r = physics::resolve(s, [](std::size_t, const std::string&, const physics::Draw& d) { return d.low(); });
  return physics::build_problem(PETSC_COMM_WORLD, m, s.source, r, 2, hstest::degree(1), true);
}

std::string error_of(const physics::SceneSpec& s) {
  try {
    (void)physics::build_effects(s.source, physics::resolve(s, [](auto, auto&, auto& d) { return d.low(); }), 2, true);
  } catch (const core::InputError& e) {
    return e.key();
  }
  return "no error";
}

}  // namespace

TEST_CASE("draws map a uniform variate into their range", "[physics][scene]") {
  using K = physics::Draw::Kind;
  physics::Draw u{K::uniform, {2.0, 4.0}}, lu{K::log_uniform, {1.0, 100.0}}, c{K::choice, {3.0, 1.0, 2.0}};
  CHECK(u.at(0.0) == 2.0);
  CHECK(u.at(0.5) == Approx(3.0));
  CHECK(lu.at(0.5) == Approx(10.0));
  CHECK(c.at(0.0) == 3.0);
  CHECK(c.at(0.99) == 2.0);
  CHECK(c.low() == 1.0);
  CHECK(c.high() == 3.0);
}

TEST_CASE("a scene that is not one solvable problem is rejected with its key path", "[physics][scene]") {
  auto s = disk_scene(true);
  CHECK(error_of(s) == "no error");
  auto two = s;
  two.effects.push_back(effect("neo_hookean", {{"E", 10.0}, {"nu", 0.2}}));
  two.effects.back().path = "effects.neo_hookean[1]";
  CHECK(error_of(two) == "effects.neo_hookean[1]");
  auto no_clamp = s;
  no_clamp.effects.erase(no_clamp.effects.begin() + 1);
  CHECK(error_of(no_clamp) == "effects");
  auto only_fixed = s;
  only_fixed.effects.erase(only_fixed.effects.begin() + 2);
  CHECK(error_of(only_fixed) == "effects");
  auto extra_key = s;
  extra_key.effects[0].params["mu"] = 1.0;
  CHECK(error_of(extra_key) == "effects.neo_hookean.mu");
  auto range = s;
  range.effects[0].params["nu"] = physics::Draw{physics::Draw::Kind::uniform, {0.6, 0.7}};
  CHECK(error_of(range) == "effects.neo_hookean.nu");
}

TEST_CASE("a fixed load enters unscaled: R(u, s) = f_int - s f_ext - f_fixed", "[physics][scene]") {
  const auto m = hstest::disk_mesh(0.2);
  auto fixed = build(disk_scene(true), m), scaled = build(disk_scene(false), m);
  REQUIRE(fixed->fixed_load() != nullptr);
  CHECK(scaled->fixed_load() == nullptr);  // nothing allocated when no load is fixed
  core::VecH u = fixed->create_vector(), r_fixed = fixed->create_vector(), r_scaled = scaled->create_vector();
  hstest::interpolate(*fixed, [](const double* x, double* v) {
    const double phi = std::max(0.0, (x[0] - 1) * (x[0] - 1) + x[1] * x[1] - 0.25);
    v[0] = 0.05 * phi * x[1], v[1] = -0.04 * phi * (1 + x[0]);
  }, u);
  // At load factor 1 both are the same problem.
  REQUIRE(fixed->residual(u, 1.0, r_fixed));
  REQUIRE(scaled->residual(u, 1.0, r_scaled));
  CHECK(hstest::rel_diff(r_fixed, r_scaled) < 1e-14);
  // At s: the difference is (1 - s) f_gravity in both the residual and the energy.
  const double s = 3.0;
  REQUIRE(fixed->residual(u, s, r_fixed));
  REQUIRE(scaled->residual(u, s, r_scaled));
  core::VecH diff = fixed->create_vector();
  HS_PETSC(VecWAXPY(diff, -1.0, r_scaled, r_fixed));  // = (s - 1) f_gravity
  PetscReal nd, nf;
  HS_PETSC(VecNorm(diff, NORM_2, &nd));
  HS_PETSC(VecNorm(fixed->fixed_load(), NORM_2, &nf));
  CHECK(nd == Approx((s - 1.0) * nf).epsilon(1e-12));
  double e_fixed, e_scaled;
  PetscScalar fu;
  REQUIRE(fixed->energy(u, s, e_fixed));
  REQUIRE(scaled->energy(u, s, e_scaled));
  HS_PETSC(VecDot(fixed->fixed_load(), u, &fu));
  CHECK(e_fixed - e_scaled == Approx((s - 1.0) * PetscRealPart(fu)).epsilon(1e-9));
  // The residual is the energy's gradient: a central difference along u.
  const double h = 1e-6;
  core::VecH up = fixed->create_vector(), um = fixed->create_vector();
  HS_PETSC(VecWAXPY(up, h, u, u));
  HS_PETSC(VecWAXPY(um, -h, u, u));
  double ep, em;
  REQUIRE(fixed->energy(up, s, ep));
  REQUIRE(fixed->energy(um, s, em));
  PetscScalar ru;
  HS_PETSC(VecDot(r_fixed, u, &ru));
  CHECK((ep - em) / (2 * h) == Approx(PetscRealPart(ru)).epsilon(1e-6));
  // Resultants count the fixed load in the applied force: total gravity = -3 |body|.
  const auto res = fixed->resultants(u, 0.0);
  CHECK(res.applied_force[1] == Approx(-3.0 * hstest::domain_measure(*fixed)).epsilon(1e-10));
}
