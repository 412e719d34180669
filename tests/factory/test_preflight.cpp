// The dataset estimate `generate` prints and checks the disk against: in 2D the mesh is shape 0's
// own (a 2D boundary is resolved by its curvature, so a uniform mesh of h undercounts the Random2D
// preset's P2 mesh 8x), and the CPU time stays within 2x of what the factory measured.
#include <catch2/catch.hpp>

#include <string>

#include "hypershape/config/dataset.hpp"
#include "hypershape/factory/dataset_scene.hpp"
#include "hypershape/factory/preflight.hpp"
#include "hypershape/factory/shape_pipeline.hpp"

using namespace hypershape;

namespace {

double shape0_vertices(const config::DatasetConfig& c) {
  return double(factory::make_shape(factory::shape_config(c, 0), std::nullopt, c.seed, 0).mesh.n_vertices());
}

}  // namespace

TEST_CASE("2D estimate: shape 0's mesh, times the degree's and the ladder's nodes per vertex", "[factory][preflight]") {
  const auto p2 = config::parse_dataset_text("preset: random2d\n", "<test>");
  const double v = shape0_vertices(p2);
  CHECK(factory::estimate_dataset(p2, std::nullopt).nodes_per_shape == 4 * v);  // P2: vertices + edges
  auto p1 = p2;
  p1.degree = 1;
  CHECK(factory::estimate_dataset(p1, std::nullopt).nodes_per_shape == v);
  // Asked for by accuracy: the estimate is at ladder level 1, from P2 the mesh refined once.
  const auto acc = config::parse_dataset_text("preset: random2d\naccuracy: {rel_l2: 0.01}\n", "<test>");
  CHECK(factory::estimate_dataset(acc, std::nullopt).nodes_per_shape == 16 * v);
}

TEST_CASE("2D estimate of the Random2D presets' CPU time: within 2x of the factory's", "[factory][preflight]") {
  // Measured 2026-11-28 (scripts/bench_generate.sh, seeds 2024 and 1001, 2 x 1000 load cases):
  // P2 h 0.12 0.147-0.222 s per load case on one core, about 2.8 core-hours for the 50000;
  // P1 h 0.04 0.034-0.044 s, about 0.55 core-hours (docs/PERFORMANCE.md, "The Random2D preset moved").
  for (const auto& [preset, core_hours] : {std::pair<std::string, double>{"random2d", 2.8}, {"random2d_p1", 0.55}}) {
    CAPTURE(preset);
    const auto e = factory::estimate_dataset(config::parse_dataset_text("preset: " + preset + "\n", "<test>"),
                                             std::nullopt);
    CHECK(e.cpu_seconds / 3600 > core_hours / 2);
    CHECK(e.cpu_seconds / 3600 < core_hours * 2);
  }
}

TEST_CASE("2D estimate with error estimates and by accuracy: the estimate's cost, and what a climb adds per level",
          "[factory][preflight]") {
  // Measured 2026-12-02 (session 68's runs, 1 core, 8 x 25 load cases of seed 4242, CPU from
  // /usr/bin/time): the random2d preset with estimates 94 s, easy_random2d with estimates 28.6 s;
  // the estimate phase costs about the solve again (77 s against 60 s of solve + alpha_search).
  for (const auto& [preset, seconds] : {std::pair<std::string, double>{"random2d", 94}, {"easy_random2d", 28.6}}) {
    CAPTURE(preset);
    const std::string text = "preset: " + preset + "\nseed: 4242\nshapes: {count: 8}\nloads: {count: 25}\n";
    const auto plain = factory::estimate_dataset(config::parse_dataset_text(text, "<test>"), std::nullopt);
    const auto with = factory::estimate_dataset(
        config::parse_dataset_text(text + "representations: {error_estimate: true}\n", "<test>"), std::nullopt);
    CHECK(with.cpu_seconds > 1.5 * plain.cpu_seconds);
    CHECK(with.cpu_seconds > seconds / 1.5);
    CHECK(with.cpu_seconds < seconds * 1.5);
    CHECK(with.cpu_seconds_per_resolve.empty());
    CHECK(with.line().find("solved again") == std::string::npos);
    // By accuracy: the level-0 cost (with estimates), and per level what a label solved again adds,
    // growing with the level's nodes; the printed line says both.
    const auto acc = factory::estimate_dataset(
        config::parse_dataset_text(text + "accuracy: {rel_l2: 0.01}\n", "<test>"), std::nullopt);
    CHECK(acc.cpu_seconds == Approx(with.cpu_seconds));
    REQUIRE(acc.cpu_seconds_per_resolve.size() == 2);
    CHECK(acc.cpu_seconds_per_resolve[0] > acc.cpu_seconds_per_load);
    CHECK(acc.cpu_seconds_per_resolve[1] > 4 * acc.cpu_seconds_per_resolve[0]);
    CHECK(acc.line().find("if every label meets the bound at level 0") != std::string::npos);
    CHECK(acc.line().find("at level 2") != std::string::npos);
  }
}
