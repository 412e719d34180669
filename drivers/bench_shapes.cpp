/// bench_shapes: where the time of one random shape goes.
///
/// For each dataset preset (default: every configs/presets/*.yaml; a preset whose base file is
/// missing is skipped with a note) and shape ids 0..R-1 (--repeats; default 5 in 2D, 3 in 3D),
/// one serial pass of
///   make_shape(config, base, seed, id)  -> the library's own timings of the accepted attempt:
///                                          draw (deformation + boundary), mesh (gmsh + quality
///                                          gate), metrics; plus the wall time of the whole call
///                                          (which also pays for every rejected draw);
///   SDF grid        geometry::SignedDistance built on the boundary, evaluated on a 128^2 grid
///                   over [-1, 1]^2 (2D) / 64^3 over [-1, 1]^3 (3D) (build + evaluate);
///   patch distance  geometry::FacetSetDistance on the Dirichlet patch facets, same grid.
/// total = make_shape wall + SDF grid + patch distance. Reported: medians over the ids (a
/// different shape per repeat: the spread is the shapes', not the clock's), and with --json
/// every per-id value. A shape whose every attempt fails is counted (`fail`), its time kept
/// apart (failed_make_shape) and left out of the medians. Serial: with several MPI ranks only
/// rank 0 works. The work is study::run_shape_bench (src/study/bench_shapes.cpp).
///
/// Sample runs (the first, a few seconds, is tests/cli/test_bench_shapes.sh):
///   bench_shapes configs/presets/random2d.yaml --repeats 1 --grid2d 32 --json bench_shapes_tiny.json
///   bench_shapes --json bench_shapes.json
///   bench_shapes configs/presets/random2d.yaml --repeats 10
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <iostream>

#include "hypershape/core/petsc_handle.hpp"
#include "hypershape/mesh/gmsh_mesher.hpp"
#include "hypershape/study/bench_shapes.hpp"
#include "hypershape/study/output.hpp"

namespace hs = hypershape;

int main(int argc, char** argv) {
  auto [ours, petsc] = hs::study::split_at_dashes(argc, argv);
  hs::study::ShapeBenchOptions set;
  CLI::App app{"Per-stage timings of random shapes (draw, mesh, signed-distance grid, patch "
               "distance) for dataset presets. Arguments after \"--\" go to PETSc."};
  app.add_option("presets", set.presets, "dataset configs (default: configs/presets/*.yaml)");
  app.add_option("--repeats", set.repeats, "shape ids 0..R-1 per preset (default 5 in 2D, 3 in 3D)")
      ->check(CLI::Range(1, 1000));
  app.add_option("--grid2d", set.grid2d, "2D grid nodes per axis")->check(CLI::Range(2, 4096));
  app.add_option("--grid3d", set.grid3d, "3D grid nodes per axis")->check(CLI::Range(2, 512));
  app.add_option("--json", set.json_path, "also write the results (medians + per-id values) here");
  try {
    app.parse(ours.count(), ours.data());
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  if (!hs::study::output_writable(set.json_path, "--json")) return 2;
  if (set.presets.empty())
    for (const char* n : {"random2d", "easy_random2d", "ood_random2d", "one_random2d", "random3d", "aug_liver"})
      set.presets.push_back(fmt::format("configs/presets/{}.yaml", n));

  int petsc_argc = petsc.count();
  char** petsc_argv = petsc.data();
  try {
    hs::core::PetscSession petsc_session(&petsc_argc, &petsc_argv, "bench_shapes\n");
    hs::mesh::GmshSession gmsh_session;
    if (hs::core::rank(PETSC_COMM_WORLD) != 0) return 0;  // serial benchmark
    if (hs::core::size(PETSC_COMM_WORLD) > 1) std::cerr << "[bench] serial benchmark: ranks > 0 idle\n";
    hs::study::run_shape_bench(set, std::cout);
  } catch (const std::exception& e) {
    std::cerr << fmt::format("error: {}\n", e.what());
    return 1;
  }
  return 0;
}
