#include "hypershape/factory/preflight.hpp"

#include <fmt/format.h>
#include <petscsys.h>
#include <sys/statvfs.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "hypershape/core/error.hpp"
#include "hypershape/factory/accuracy.hpp"
#include "hypershape/factory/dataset_scene.hpp"
#include "hypershape/factory/shape_pipeline.hpp"
#include "hypershape/io/dataset_shard.hpp"

namespace hypershape::factory {

namespace fs = std::filesystem;

namespace {

/// 2D: the vertices of shape 0 as the dataset draws and meshes it (0 if it has no acceptable draw).
double pilot_vertices(const config::DatasetConfig& cfg, const std::optional<geometry::Boundary>& base) {
  try {
    return double(make_shape(shape_config(cfg, 0), base, cfg.seed, 0).mesh.n_vertices());
  } catch (const std::runtime_error&) {
    return 0.0;
  }
}

/// Rough CPU seconds of one typical load case on `nodes` nodes of degree `degree` (its error
/// estimate included when `estimate`). Measured per load case (the phases of
/// `scripts/bench_generate.sh`, 1 rank, 2026-11-28): 2D P1 5.3k unknowns 0.034-0.044 s, 2D P2
/// 13.5k unknowns 0.15-0.22 s (random2d_p1, random2d; two seeds); 3D P2 3.3k unknowns 7 s; cost
/// grows faster than the unknowns. The estimate costs about the solve again (the run reports'
/// phases, 2026-12-02: error_estimate 77 s against 60 s of solve + alpha_search on Random2D 8 x 25,
/// the whole EasyRandom2D run 1.9x the solve-only estimate).
double cpu_seconds_per_load(int dim, int degree, double nodes, bool estimate) {
  const double c = dim == 3 ? 1.9e-4 : degree == 1 ? 5.6e-7 : 7.9e-7;
  return (0.005 + c * std::pow(nodes * dim, 1.3)) * (estimate ? 2.0 : 1.0);
}

}  // namespace

DatasetEstimate estimate_dataset(const config::DatasetConfig& cfg, const std::optional<geometry::Boundary>& base) {
  // 3D: a shape fills about 2.5 of the box's 8; vertices of a tetrahedral mesh of size h: 1.5 / h^3
  // per volume. 2D: shape 0's mesh (without a draw: 2.5 of the box's 4, 1.15 / h^2 per area).
  // P2 adds edge nodes (x4 in 2D, x8 in 3D); a uniform refinement multiplies the vertices by 4 / 8.
  const int d = cfg.shapes.dim;
  const double pilot = d == 2 ? pilot_vertices(cfg, base) : 0.0;
  auto nodes_at = [&](int k) {  // nodes of a shape at the ladder's level k (0: the config's own mesh)
    const AccuracyLevel level = accuracy_level(cfg, k);
    const double vertices = pilot > 0  ? pilot * std::pow(4.0, level.refinements)
                            : d == 2   ? 2.5 * 1.15 / (level.h * level.h)
                                       : 2.5 * 1.5 / (level.h * level.h * level.h);
    return std::pair{vertices, vertices * (level.degree == 1 ? 1.0 : (d == 2 ? 4.0 : 8.0))};
  };
  // A dataset asked for by accuracy is sized at its ladder's level 1 (a shape is stored at its
  // finest label's level, known only once it is solved; Random2D at rel_l2 0.01 stored 5 of 8
  // shapes at level 2, 4x these sizes, and 3 at level 1 (2026-12-02, session 68): docs/ACCURACY.md).
  const auto [vertices, n] = nodes_at(cfg.accuracy.enabled() ? std::min(1, cfg.accuracy.max_level) : 0);
  const double grid = cfg.representations.grid ? std::pow(double(cfg.representations.grid_size), d) : 0.0;
  const double pc = cfg.representations.point_cloud ? 1.0 : 0.0;
  const double per_shape = n * d * 8 + vertices * (d + 1) * 2 * 8 + n * 2 + pc * n * 16 + grid * 9;
  const double per_load = n * d * 8 * (1 + pc) + grid * d * 4 * 2 + 200;
  DatasetEstimate e;
  e.nodes_per_shape = n;
  // Raw bytes plus HDF5 metadata and chunk indexes (~50 kB per shape); deflate gains little on
  // noisy floats. Measured: random2d 1 shape x 50 load cases 16 MB estimated / 10.8 MB written;
  // a 2D slice at h 0.1 with 64^2 grids 2.0 / 2.9 MB; random3d 1 x 4 28 / 16 MB.
  e.bytes_per_shape = per_shape + cfg.loads.count * per_load + 50e3;
  // Every load case is solved at level 0; what the labels that climb cost on top is known only as
  // they are solved: per level, a typical load case's cost there (a label that climbs is a hard
  // one: Random2D's took several times that, docs/ACCURACY.md).
  const bool estimate = cfg.representations.error_estimate;
  e.cpu_seconds_per_load = cpu_seconds_per_load(d, cfg.degree, nodes_at(0).second, estimate);
  for (int k = 1; cfg.accuracy.enabled() && k <= cfg.accuracy.max_level; ++k)
    e.cpu_seconds_per_resolve.push_back(cpu_seconds_per_load(d, accuracy_level(cfg, k).degree, nodes_at(k).second, true));
  e.bytes = e.bytes_per_shape * double(cfg.n_shapes);
  // A shape costs its draw and mesh too (~0.2 s in 2D, ~5 s in 3D at the presets' sizes).
  e.cpu_seconds = (e.cpu_seconds_per_load * cfg.loads.count + (d == 2 ? 0.2 : 5.0)) * double(cfg.n_shapes);
  return e;
}

std::string DatasetEstimate::line() const {
  const bool ladder = !cpu_seconds_per_resolve.empty();
  std::string s = fmt::format("about {} on disk and {} of CPU for the whole dataset{} (rough: ~{:.0f} nodes per shape)",
                              format_bytes(bytes), format_duration(cpu_seconds),
                              ladder ? " if every label meets the bound at level 0" : "", nodes_per_shape);
  if (!ladder) return s;
  s += "; each label solved again adds about";
  for (std::size_t k = 0; k < cpu_seconds_per_resolve.size(); ++k)
    s += fmt::format("{} {:.2g} s at level {}", k ? "," : "", cpu_seconds_per_resolve[k], k + 1);
  return s + " (a typical load case's; how many climb shows only as they are solved)";
}

std::string format_bytes(double b) {
  const char* units[] = {"B", "kB", "MB", "GB", "TB", "PB", "EB"};
  int u = 0;
  while (b >= 1000 && u < 6) b /= 1000, ++u;
  return fmt::format("{:.{}f} {}", b, b < 10 && u > 0 ? 1 : 0, units[u]);
}

std::string format_duration(double s) {
  if (!std::isfinite(s) || s < 0) return "?";
  if (s >= 86400 * 365.0) return fmt::format("{:.3g} years", s / (86400 * 365.0));
  const long t = long(s + 0.5);
  if (t >= 86400) return fmt::format("{}d{:02d}h", t / 86400, (t % 86400) / 3600);
  return t >= 3600 ? fmt::format("{}h{:02d}m", t / 3600, (t % 3600) / 60) : fmt::format("{}m{:02d}s", t / 60, t % 60);
}

namespace {

/// Free bytes of the file system that holds `dir` (or would: its nearest existing parent).
double free_bytes(const std::string& dir) {
  fs::path p = fs::absolute(dir);
  std::error_code ec;
  while (!p.empty() && !fs::exists(p, ec)) p = p.parent_path();
  struct statvfs s {};
  if (statvfs(p.c_str(), &s) != 0) return INFINITY;
  return double(s.f_bavail) * double(s.f_frsize);
}

}  // namespace

void check_resources(const config::DatasetConfig& cfg, const DatasetEstimate& e, double bytes_to_write,
                     const std::string& output_dir, bool force) {
  const std::string what = fmt::format("{} shapes x {} load cases take about {} on disk and {} of CPU", cfg.n_shapes,
                                       cfg.loads.count, format_bytes(e.bytes), format_duration(e.cpu_seconds));
  const std::string remedy = "lower shapes.count (or loads.count, representations.grid_size), or pass --force";
  if (force) return;
  if (e.bytes > max_dataset_bytes)
    throw core::InputError(cfg.source, "shapes.count",
                           fmt::format("{}, over the bound of {} (a rough estimate): {}", what,
                                       format_bytes(max_dataset_bytes), remedy));
  const double avail = free_bytes(output_dir);
  if (bytes_to_write > avail)
    throw core::InputError(cfg.source, "shapes.count",
                           fmt::format("{}; {} still to write, but the file system of {} has {} free: free space, "
                                       "choose another -o, or {}", what, format_bytes(bytes_to_write), output_dir,
                                       format_bytes(avail), remedy));
}

void check_shard_space(const std::string& output_dir, std::int64_t shard, double shard_bytes) {
  const double avail = free_bytes(output_dir);
  if (avail < 0.5 * shard_bytes)
    throw io::StorageError(fmt::format("stopped before shard {}: the file system of {} has {} free, a shard takes "
                                       "about {}; the shards written before are complete: free space and run the "
                                       "same command again to resume", shard, output_dir, format_bytes(avail),
                                       format_bytes(shard_bytes)));
}

std::vector<UserOption> user_options(const config::DatasetConfig& cfg, const std::vector<std::string>& command_line) {
  std::vector<UserOption> out;
  for (const auto& [k, v] : cfg.petsc) out.push_back({k, "petsc." + k.substr(1)});
  for (const auto& k : command_line) out.push_back({k, "command line"});
  return out;
}

}  // namespace hypershape::factory
