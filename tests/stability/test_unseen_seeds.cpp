/// Issue 23: load cases of unseen seeds (Random2D, 20 shapes x 50 load cases per seed) that the
/// solver of 2026-11-24 lost after branch switches. Each must reach a verified stable equilibrium.
#include <catch2/catch.hpp>

#include <cstdlib>
#include <iostream>
#include <string>

#include "hypershape/config/dataset.hpp"
#include "hypershape/factory/dataset_scene.hpp"
#include "hypershape/factory/load_cases.hpp"
#include "hypershape/factory/shape_pipeline.hpp"
#include "hypershape/solver/nonlinear.hpp"
#include "support/helpers.hpp"

using namespace hypershape;

namespace {

int env_int(const char* name, int fallback) {
  const char* v = std::getenv(name);
  return v ? std::atoi(v) : fallback;
}

}  // namespace

/// Replays a shape's load cases 0..LOAD as the factory does (one solver, load cases in order):
///   SEED=777 SHAPE=3 LOAD=47 PETSC_OPTIONS="-info :snes" unit_tests "[unseen_replay]"
TEST_CASE("Replay one shape's load cases as the factory does", "[.][unseen_replay]") {
  auto cfg = config::parse_dataset_file(std::string(HS_SOURCE_DIR) + "/configs/presets/random2d.yaml");
  cfg.loads.count = 50;
  cfg.seed = std::uint64_t(env_int("SEED", 777));
  const int shape_id = env_int("SHAPE", 3), last = env_int("LOAD", 47), first = env_int("FROM", 0);
  const auto shape = factory::make_shape(factory::shape_config(cfg, shape_id), std::nullopt, cfg.seed, shape_id);
  const auto loads = factory::draw_load_cases(shape, cfg.loads, cfg.seed, factory::n_tractions(cfg));
  auto sp = factory::make_shape_problem(PETSC_COMM_WORLD, cfg, shape, loads[0]);
  solver::NonlinearSolver ns(*sp.problem, cfg.solver);
  for (int l = first; l <= last; ++l) {
    sp.set_load_case(cfg, shape, loads[std::size_t(l)]);
    ns.reset();
    const auto r = ns.solve_for_target(loads[std::size_t(l)].target);
    if (!r.converged || l == last || r.newton_iterations > 40)
      std::cout << "seed " << cfg.seed << " shape " << shape_id << " load " << l << " target "
                << loads[std::size_t(l)].target << ": " << (r.converged ? "ok" : "FAILED") << ", "
                << r.newton_iterations << " its (" << r.recovery_iterations << " recovery): " << r.reason
                << "\n";
  }
}
