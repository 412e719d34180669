// The dataset presets embedded in the binary: the paper's eight (Table 1) are there, each parses
// by name as it does from its file, and the directory presets (liver, one_liver) resolve to the
// shipped stand-in surfaces: one shape per file in name order, no deformation.
#include <catch2/catch.hpp>

#include <algorithm>
#include <filesystem>
#include <set>
#include <string>

#include "hypershape/config/dataset.hpp"
#include "hypershape/core/input_error.hpp"
#include "hypershape/mesh/surface_file.hpp"

using namespace hypershape;

// Named for the unity build (HS_UNITY_BUILD): files of one batch share a scope.
namespace test_presets {
namespace {

config::DatasetConfig by_name(const std::string& text) {
  return config::parse_dataset_text(text, "<test>");
}

/// "key | message" of the InputError the config text raises, or "no error".
std::string error_of(const std::string& text) {
  try {
    (void)by_name(text);
  } catch (const core::InputError& e) {
    return e.key() + " | " + e.what();
  }
  return "no error";
}

std::string shipped_livers() { return std::string(HS_SOURCE_DIR) + "/configs/surfaces/livers"; }

}  // namespace

TEST_CASE("the paper's eight presets (and random2d_p1) are embedded and parse by name as from their files",
          "[config][presets]") {
  std::set<std::string> names;
  for (const auto& p : config::presets()) {
    INFO(p.name);
    names.insert(p.name);
    const auto a = by_name(std::string("preset: ") + p.name + "\n");
    const auto b = config::parse_dataset_file(std::string(p.directory) + "/" + p.name + ".yaml");
    CHECK(a.name == p.name);
    CHECK(a.n_shapes == b.n_shapes);
    CHECK(a.loads.count == b.loads.count);
    CHECK(a.shapes.base_file == b.shapes.base_file);
    CHECK(a.shapes.base_files == b.shapes.base_files);
  }
  for (const char* n : {"random2d", "easy_random2d", "ood_random2d", "one_random2d", "random3d",
                        "aug_liver", "liver", "one_liver", "random2d_p1"})
    CHECK(names.count(n) == 1);
}

TEST_CASE("random2d is P2 at h 0.12; random2d_p1 is the former P1 preset with the same family",
          "[config][presets]") {
  const auto p2 = by_name("preset: random2d\n"), p1 = by_name("preset: random2d_p1\n");
  CHECK((p2.degree == 2 && p2.shapes.h == 0.12));
  CHECK((p1.degree == 1 && p1.shapes.h == 0.04 && p1.shapes.min_feature_fraction == 0.1));
  // The same shape family: flows, patch, loads, and the same absolute neck threshold (0.004).
  const auto& a = p2.shapes.deformation.steps;
  const auto& b = p1.shapes.deformation.steps;
  REQUIRE(a.size() == b.size());
  for (std::size_t i = 0; i < a.size(); ++i) CHECK((a[i].sigma == b[i].sigma && a[i].m == b[i].m));
  CHECK(p2.shapes.dirichlet_radius == p1.shapes.dirichlet_radius);
  CHECK((p2.n_shapes == p1.n_shapes && p2.loads.count == p1.loads.count && p2.seed == p1.seed));
  CHECK(p2.shapes.min_feature_fraction * p2.shapes.h == Approx(0.004).epsilon(1e-3));
  CHECK(p1.shapes.min_feature_fraction * p1.shapes.h == Approx(0.004).epsilon(1e-12));
}

TEST_CASE("liver and one_liver: one shape per shipped surface file, no deformation",
          "[config][presets]") {
  const std::vector<std::string> files = mesh::surface_files_in(shipped_livers());
  REQUIRE(files.size() >= 2);
  CHECK(std::is_sorted(files.begin(), files.end()));

  const auto liver = by_name("preset: liver\n");
  // Table 1: 100 load cases per shape, no deformation; 3D datasets: r 0.4, gamma 0.1, grid 64.
  CHECK(liver.n_shapes == std::int64_t(files.size()));  // count: the number of files
  CHECK(liver.shapes.base == "directory");
  CHECK(liver.shapes.base_files == files);
  CHECK(liver.shapes.deformation.steps.empty());
  CHECK(liver.shapes.dim == 3);
  CHECK(liver.shapes.dirichlet_radius == 0.4);
  CHECK(liver.loads.count == 100);
  CHECK(liver.loads.gamma == 0.1);
  CHECK(liver.representations.grid_size == 64);
  // The resolved config (the dataset's identity) writes the count and lists the files.
  CHECK(liver.text.find("count: " + std::to_string(files.size())) != std::string::npos);
  CHECK(liver.text.find("0: liver_000.stl") != std::string::npos);

  const auto one = by_name("preset: one_liver\n");
  CHECK(one.n_shapes == 1);
  CHECK(one.loads.count == 10000);
  REQUIRE(one.shapes.base_files.size() == 1);
  CHECK(one.shapes.base_files[0] == files[0]);

  // count < files takes the first `count` by name; steps may deform each file.
  const auto two = by_name("preset: liver\nshapes: {count: 2, steps: [[0.2, 1]]}\n");
  CHECK(two.n_shapes == 2);
  CHECK(two.shapes.base_files == std::vector<std::string>(files.begin(), files.begin() + 2));
  CHECK(two.shapes.deformation.steps.size() == 1);
}

TEST_CASE("a directory family's keys are checked", "[config][presets]") {
  CHECK_THAT(error_of("preset: liver\nshapes: {count: 1000}\n"), Catch::StartsWith("shapes.count"));
  CHECK_THAT(error_of("preset: liver\nshapes: {base_dir: /nonexistent/livers}\n"),
             Catch::StartsWith("shapes.base_dir") && Catch::Contains("no such directory"));
  CHECK_THAT(error_of("preset: random3d\nshapes: {base_dir: " + shipped_livers() + "}\n"),
             Catch::StartsWith("shapes.base_dir") && Catch::Contains("only allowed with base: directory"));
  CHECK_THAT(error_of("preset: random2d\nshapes: {base: directory, base_dir: " + shipped_livers() + "}\n"),
             Catch::StartsWith("shapes.base"));
  CHECK_THAT(error_of("preset: liver\nshapes: {base_file: x.stl}\n"), Catch::StartsWith("shapes.base_file"));
  CHECK_THAT(error_of("preset: random3d\nshapes: {count: null}\n"), Catch::StartsWith("shapes.count"));
}

TEST_CASE("mesh.h: a 3D mesh coarser than its shape, checked", "[config][presets]") {
  const auto c = by_name("preset: random3d\nshapes: {h: 0.1}\nmesh: {degree: 2, h: 0.3}\n");
  CHECK(c.shapes.h == 0.1);
  CHECK(c.shapes.mesh_h == 0.3);
  CHECK(c.degree == 2);
  // The 3D presets set it (merged under an override of the degree alone); 2D ones do not.
  CHECK(by_name("preset: random3d\nmesh: {degree: 1}\n").shapes.mesh_h == 0.3);
  CHECK(by_name("preset: liver\n").shapes.mesh_h == 0.2);
  CHECK(by_name("preset: random2d\n").shapes.mesh_h == 0.0);
  CHECK_THAT(error_of("preset: random2d\nmesh: {h: 0.1}\n"),
             Catch::StartsWith("mesh.h") && Catch::Contains("only for 3D"));
  CHECK_THAT(error_of("preset: random3d\nshapes: {h: 0.1}\nmesh: {h: 0.05}\n"),
             Catch::StartsWith("mesh.h") && Catch::Contains("[shapes.h = 0.1, 0.5]"));
  CHECK_THAT(error_of("preset: random3d\nmesh: {h: big}\n"), Catch::StartsWith("mesh.h"));
}

TEST_CASE("random3d labels with the mean dilatation; material.dilatation is the shorthand, checked",
          "[config][presets]") {
  auto dilatation = [](const config::DatasetConfig& c) -> std::string {
    for (auto i : c.scene.find("neo_hookean"))
      if (auto it = c.scene.effects[i].params.find("dilatation"); it != c.scene.effects[i].params.end())
        return std::get<std::string>(it->second);
    return "(none)";
  };
  const auto r3 = by_name("preset: random3d\n");
  CHECK(r3.material.dilatation == "mean");
  CHECK(dilatation(r3) == "mean");
  CHECK(r3.shapes.mesh_h == 0.3);
  CHECK(r3.shapes.surface_h == 0.22);
  CHECK(r3.shapes.rim_size == 0.125);
  CHECK(r3.solver.tangent.single_factor);
  CHECK_FALSE(by_name("preset: random2d\n").solver.tangent.single_factor);
  for (const char* n : {"aug_liver", "liver", "one_liver"})  // every 3D preset factorises in single precision
    CHECK(by_name(std::string("preset: ") + n + "\n").solver.tangent.single_factor);
  // The other presets' scenes are what they were: no dilatation key at all.
  CHECK(dilatation(by_name("preset: random2d\n")) == "(none)");
  CHECK(dilatation(by_name("preset: aug_liver\n")) == "(none)");
  // A config's own material wins; its own effects replace the shorthand (pointwise unless said).
  CHECK(dilatation(by_name("preset: random3d\nmaterial: {dilatation: pointwise}\n")) == "(none)");
  CHECK(dilatation(by_name("preset: random3d\neffects:\n  neo_hookean: {E: 500, nu: 0.49}\n"
                           "  dirichlet_patch: {radius: 0.4}\n  gaussian_traction: {gamma: 0.1}\n")) == "(none)");
  CHECK_THAT(error_of("preset: random2d\nmaterial: {dilatation: avg}\n"),
             Catch::StartsWith("material.dilatation") && Catch::Contains("pointwise, mean"));
}

}  // namespace test_presets
