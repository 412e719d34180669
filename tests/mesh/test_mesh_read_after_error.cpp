/// One unreadable mesh file must not make every later read_mesh_file in the process fail.
/// (Hidden test, tag [.]: it runs in its own CTest process via the per-file registration, so a
/// failure here cannot cascade into other tests.)
#include <catch2/catch.hpp>
#include <filesystem>

#include "hypershape/core/error.hpp"
#include "support/helpers.hpp"

using namespace hypershape;

TEST_CASE("A good mesh file reads fine after a bad one", "[mesh][.]") {
  const std::string dir = "/usr/share/petsc/3.18/share/petsc/datafiles/meshes/";
  const std::string good = dir + "square.msh", bad = dir + "texas.msh";  // texas: no nodes
  REQUIRE(std::filesystem::exists(good));
  REQUIRE(std::filesystem::exists(bad));
  const auto before = mesh::read_mesh_file(good);
  REQUIRE(before.n_cells() > 0);
  try {
    mesh::read_mesh_file(bad);
    FAIL("no exception");
  } catch (const core::InputError& e) {
    CHECK(e.file() == bad);
  }
  mesh::MeshData after;
  try {
    after = mesh::read_mesh_file(good);
  } catch (const core::InputError& e) {
    FAIL("reading " << good << " after " << bad << " failed: " << e.what());
  }
  CHECK(after.cells == before.cells);
  CHECK(after.coords == before.coords);
}
