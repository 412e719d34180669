/// An unreadable mesh file is an InputError naming the file, and it must not break later
/// meshing in the same process. (Hidden test, tag [.]: it runs in its own CTest process via the
/// per-file registration, so a failure here cannot cascade into other tests.)
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>

#include "hypershape/core/error.hpp"
#include "support/helpers.hpp"

using namespace hypershape;

TEST_CASE("A file that is not a mesh is an InputError and meshing still works after it",
          "[mesh][.]") {
  const auto path =
      (std::filesystem::temp_directory_path() / "hypershape_test_garbage.msh").string();
  std::ofstream(path) << "this is not a gmsh file\n1 2 3\n";
  try {
    mesh::read_mesh_file(path);
    FAIL("no exception");
  } catch (const core::InputError& e) {
    CHECK(e.file() == path);
    CHECK_THAT(e.what(), Catch::Contains(path));
  }
  std::filesystem::remove(path);

  // The process goes on meshing (a data factory reads many files and meshes many shapes).
  mesh::MeshOptions mo;
  mo.h = 0.1;
  const mesh::MeshData m = mesh::mesh_disk(mo, mesh::ClampRegion{{1.0, 0.0, 0.0}, 0.5});
  CHECK(m.n_cells() > 100);
  int n_ends = 0;
  for (std::int64_t v = 0; v < m.n_vertices(); ++v) {
    const double x = m.coords[2 * v], y = m.coords[2 * v + 1];
    n_ends += std::abs(std::hypot(x - 1.0, y) - 0.5) <= 1e-12 &&
              std::abs(std::hypot(x, y) - 1.0) <= 1e-12;
  }
  CHECK(n_ends == 2);
  CHECK(mesh::mesh_box(3, 1.0, 0.5).n_cells() > 0);
}
