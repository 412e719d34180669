#pragma once
/// The shape benchmark (drivers/bench_shapes.cpp): where the time of one random shape goes.
#include <iosfwd>
#include <string>
#include <vector>

namespace hypershape::study {

struct ShapeBenchOptions {
  std::vector<std::string> presets;  ///< dataset config files, in order
  int repeats = 0;                   ///< shape ids 0..repeats-1; 0: 5 in 2D, 3 in 3D
  int grid2d = 128;                  ///< signed-distance grid nodes per axis
  int grid3d = 64;
  std::string json_path;  ///< also write the results here (empty: no JSON)
};

/// For each preset and shape id: make_shape (draw, mesh, metrics, with redraws), a signed
/// distance grid and the distance to the Dirichlet patch, timed; medians over the ids are
/// printed as a table on `table` (and, with every per-id value, written to json_path after
/// every preset). A preset that cannot be read, or whose base file is missing, is skipped with
/// a note. Serial: call on one rank, inside a PETSc and a gmsh session.
void run_shape_bench(const ShapeBenchOptions& options, std::ostream& table);

}  // namespace hypershape::study
