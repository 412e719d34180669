#include "hypershape/factory/commands.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <filesystem>

#include "hypershape/config/scene.hpp"
#include "hypershape/core/collective.hpp"
#include "hypershape/core/input_error.hpp"
#include "hypershape/core/log.hpp"
#include "hypershape/core/petsc_handle.hpp"
#include "hypershape/core/timer.hpp"
#include "hypershape/factory/dataset_index.hpp"
#include "hypershape/factory/shape_set.hpp"
#include "hypershape/io/dataset_shard.hpp"
#include "hypershape/io/shape_file.hpp"
#include "hypershape/io/solution_file.hpp"
#include "hypershape/mesh/gmsh_mesher.hpp"

namespace hypershape::factory {

namespace {

/// Checks that OUT can be created, before any work (nothing is written here).
void check_output_path(const std::string& out) {
  namespace fs = std::filesystem;
  fs::path p(out);
  if (p.extension() != ".h5") throw core::InputError("", "-o", "output must end in .h5, got '" + out + "'");
  fs::path dir = p.parent_path().empty() ? fs::path(".") : p.parent_path();
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw core::InputError("", "-o", "directory does not exist: " + dir.string());
  if (access(dir.c_str(), W_OK) != 0) throw core::InputError("", "-o", "directory is not writable: " + dir.string());
}

}  // namespace

config::DatasetConfig dataset_to_generate(const std::string& config_path, const std::string& preset, bool mini) {
  const config::DatasetConfig cfg =
      !preset.empty()       ? config::preset_dataset(preset)
      : config_path.empty() ? config::parse_dataset_text(config::default_dataset_text(), "<default dataset>")
                            : config::parse_dataset_file(config_path);
  return mini ? config::mini_dataset(cfg) : cfg;
}

int run_generate(MPI_Comm comm, const config::DatasetConfig& cfg, const std::string& out,
                 GenerateOptions gen) {
  mesh::GmshSession gmsh;
  gen.output_dir = out.empty() ? "results/" + cfg.name : out;
  const auto report = generate(comm, cfg, gen);
  core::info(comm, "[generate] done{}:\n{}", report.indexed ? " (dataset complete: manifest, splits, stats written)"
                                                             : " (slice written; run `hypershape index` when all are)",
             report_table(report));
  return 0;
}

int run_index(MPI_Comm comm, const std::string& dir) {
  IndexReport r;
  core::on_root(comm, [&] { r = index_dataset(dir); });
  std::string missing;
  for (auto k : r.missing_shards) missing += (missing.empty() ? "" : ", ") + std::to_string(k);
  core::info(comm, "{}: {} shards, {} shapes ({} failed), {} load cases converged, {} failed{}", dir, r.shards,
             r.shapes_ok + r.shapes_failed, r.shapes_failed, r.loads_ok, r.loads_failed,
             r.complete() ? "; complete" : "; INCOMPLETE, missing shards: " + missing);
  int complete = r.complete();
  MPI_Bcast(&complete, 1, MPI_INT, 0, comm);
  return complete ? 0 : 4;
}

int run_shapes(MPI_Comm comm, const std::string& config_path, const std::string& out, std::int64_t first,
               std::int64_t count) {
  check_output_path(out);
  mesh::GmshSession gmsh;  // one gmsh session for all shapes of this rank
  const config::DatasetConfig cfg = config::parse_dataset_file(config_path);
  if (count < 0) count = cfg.n_shapes - first;
  if (count < 1 || first + count > cfg.n_shapes)
    throw core::InputError(config_path, "shapes.count",
                           fmt::format("--first {} and --count {} must select shapes within [0, {})", first,
                                       count, cfg.n_shapes));
  core::info(comm, "{}: drawing shapes {}..{} on {} rank(s)", cfg.name, first, first + count - 1, core::size(comm));
  const double t0 = core::now_seconds();
  const auto records = make_shape_range(comm, cfg, first, count);
  int n_failed = 0;
  if (core::rank(comm) == 0) {
    for (const auto& r : records) n_failed += r.numbers.at("failed") != 0;
    io::write_shapes(out, records, cfg.text, cfg.name, cfg.seed);
  }
  MPI_Bcast(&n_failed, 1, MPI_INT, 0, comm);
  core::info(comm, "{} shapes ({} failed) in {:.1f} s -> {}", count, n_failed, core::now_seconds() - t0, out);
  return n_failed ? 3 : 0;
}

int run_solve(MPI_Comm comm, const std::string& scene_path, const std::string& out, const SceneRuns& runs) {
  // Validate everything that can be validated before any work or output.
  check_output_path(out);
  config::Scene scene = scene_path.empty()
                            ? config::parse_scene_text(config::default_scene_text(), "<default scene>")
                            : config::parse_scene_file(scene_path);
  auto outcome = solve_scene(comm, scene, runs);
  auto t0 = core::now_seconds();
  if (core::rank(comm) == 0) io::write_solution(out, outcome.record);
  outcome.times.add("write", core::now_seconds() - t0);
  core::info(comm, "{} -> {}", summary_line(outcome), out);
  return outcome.converged ? 0 : 3;
}

}  // namespace hypershape::factory
