#pragma once
/// One solved scene on disk: HDF5 (+ an XDMF file beside it for ParaView). Only io/ includes
/// hdf5.h. Files appear atomically: written under a temporary name, closed, renamed.
///
/// Layout (docs/FORMAT.md):
///   /mesh/nodes            n_nodes x dim    node coordinates (vertices first, then P2 edge nodes)
///   /mesh/cells            n_cells x k      VTK-ordered node indices (k = 3, 6, 4 or 10)
///   /fields/displacement   n_nodes x dim    u at the nodes
///   /inputs/scene          string           the scene file as read
///   /timings/seconds       n_solves         seconds of each solve (target, alpha, ... with
///                                           several: `hypershape solve --repeat/--targets`)
///   attributes on /: dim, degree, n_vertices, alpha, target, max_displacement, converged,
///                    reason, newton_iterations, hypershape_version
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace hypershape::io {

struct SolutionRecord {
  int dim = 2, degree = 1;
  std::int64_t n_vertices = 0;
  std::vector<double> nodes;         ///< n_nodes x dim
  std::vector<std::int64_t> cells;   ///< n_cells x nodes_per_cell
  std::vector<double> displacement;  ///< n_nodes x dim
  std::string scene_text;
  std::map<std::string, double> numbers;       ///< scalar attributes
  std::map<std::string, std::string> strings;  ///< string attributes
  std::map<std::string, std::vector<double>> timings;  ///< /timings/<name>, one entry per solve
};

/// Writes `path` (.h5) and `path` with .xdmf. Not collective: call on one rank. Throws
/// std::runtime_error on I/O failure and leaves no partial file behind.
void write_solution(const std::string& path, const SolutionRecord& rec);

/// Reads back the arrays written by write_solution (for tests and tools).
SolutionRecord read_solution(const std::string& path);

}  // namespace hypershape::io
