/// Meshing is a pure function of its inputs: the same call gives the same MeshData, bit for
/// bit, within a process and across processes (DESIGN: "every random draw is a pure function of
/// (dataset seed, shape id, load id): same data on 1 rank or 1000"; the slices of a SLURM array
/// must be byte-for-byte the dataset one process would make).
#include <catch2/catch.hpp>

#include "support/helpers.hpp"

using namespace hypershape;

TEST_CASE("2D meshes are deterministic", "[mesh][determinism]") {
  mesh::MeshOptions mo;
  mo.h = 0.1;
  mo.clamp_size = 0.02;
  const mesh::ClampRegion clamp{{0.6, 0.8, 0.0}, 0.5};
  const auto d1 = mesh::mesh_disk(mo, clamp);
  (void)mesh::mesh_box(2, 1.0, 0.13);  // something else in between
  const auto d2 = mesh::mesh_disk(mo, clamp);
  CHECK(d1.n_cells() > 100);
  CHECK(hstest::same_mesh(d1, d2));
  CHECK(hstest::same_mesh(mesh::mesh_box(2, 1.0, 0.1), mesh::mesh_box(2, 1.0, 0.1)));
}

TEST_CASE("3D meshes are deterministic", "[mesh][determinism]") {
  mesh::MeshOptions mo;
  mo.h = 0.3;
  const mesh::ClampRegion clamp{{0.0, 0.0, 1.0}, 0.6};
  for (int repeat = 0; repeat < 3; ++repeat) {
    const auto b1 = mesh::mesh_box(3, 1.0, 0.25), b2 = mesh::mesh_box(3, 1.0, 0.25);
    INFO("box cells " << b1.n_cells() << " vs " << b2.n_cells());
    CHECK(hstest::same_mesh(b1, b2));
    const auto s1 = mesh::mesh_ball(mo, clamp), s2 = mesh::mesh_ball(mo, clamp);
    INFO("ball cells " << s1.n_cells() << " vs " << s2.n_cells());
    CHECK(hstest::same_mesh(s1, s2));
  }
}
