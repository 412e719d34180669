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
/// rank 0 works.
///
/// Sample runs:
///   bench_shapes --json bench_shapes.json
///   bench_shapes configs/presets/random2d.yaml --repeats 10
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "driver_support.hpp"
#include "hypershape/config/dataset.hpp"
#include "hypershape/core/error.hpp"
#include "hypershape/core/petsc_handle.hpp"
#include "hypershape/core/timer.hpp"
#include "hypershape/factory/shape_pipeline.hpp"
#include "hypershape/geometry/distance.hpp"
#include "hypershape/mesh/gmsh_mesher.hpp"

namespace hs = hypershape;
namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

struct Settings {
  std::vector<std::string> presets;
  int repeats = 0;  ///< 0: 5 in 2D, 3 in 3D
  int grid2d = 128;
  int grid3d = 64;
  std::string json_path;
};

/// One preset: per-id samples.
struct PresetRecord {
  std::string file, name;
  int dim = 0;
  double h = 0;
  int repeats = 0;
  std::map<std::string, std::vector<double>> seconds;  ///< one per id
  std::map<std::string, std::vector<double>> values;   ///< counts, one per id
  std::vector<std::string> notes;
  std::string error;
};

double median(std::vector<double> v) {
  v.erase(std::remove_if(v.begin(), v.end(), [](double x) { return !std::isfinite(x); }), v.end());
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

double med(const std::map<std::string, std::vector<double>>& m, const std::string& k) {
  auto it = m.find(k);
  return it == m.end() ? NAN : median(it->second);
}

double cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

std::string load_average() {
  std::ifstream f("/proc/loadavg");
  std::string a, b, c;
  f >> a >> b >> c;
  return a + " " + b + " " + c;
}

/// n^dim nodes of the uniform grid over [-1, 1]^dim, x fastest.
std::vector<double> grid_points(int dim, int n) {
  std::vector<double> x;
  const std::size_t total = dim == 2 ? std::size_t(n) * n : std::size_t(n) * n * n;
  x.reserve(total * dim);
  auto c = [n](int i) { return -1.0 + 2.0 * i / (n - 1); };
  for (int k = 0; k < (dim == 3 ? n : 1); ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        x.push_back(c(i));
        x.push_back(c(j));
        if (dim == 3) x.push_back(c(k));
      }
  return x;
}

std::string fmt_time(double s) {
  if (!std::isfinite(s)) return "-";
  if (s < 1e-3) return fmt::format("{:.0f}us", s * 1e6);
  if (s < 1.0) return fmt::format("{:.1f}ms", s * 1e3);
  if (s < 100.0) return fmt::format("{:.2f}s", s);
  return fmt::format("{:.0f}s", s);
}

std::string fmt_count(double v) { return std::isfinite(v) ? fmt::format("{:.0f}", v) : "-"; }

/// "N attempts: stage k, ... (first: reason)" from make_shape's failure message, whose lines
/// after the first read "  attempt A (stage): reason".
std::string summarise_failure(const std::string& what) {
  std::map<std::string, int> stages;
  std::string first;
  int n = 0;
  std::size_t pos = what.find('\n');
  while (pos != std::string::npos) {
    const std::size_t end = what.find('\n', pos + 1);
    const std::string line = what.substr(pos + 1, end == std::string::npos ? end : end - pos - 1);
    pos = end;
    const std::size_t open = line.find('('), close = line.find("): ");
    if (open == std::string::npos || close == std::string::npos || close < open) continue;
    ++n;
    ++stages[line.substr(open + 1, close - open - 1)];
    if (first.empty()) first = line.substr(close + 3);
  }
  if (n == 0) return what.substr(0, what.find('\n'));
  std::string out = fmt::format("{} attempts:", n);
  for (const auto& [stage, k] : stages) out += fmt::format(" {} {}", stage, k);
  return out + " (first: " + first + ")";
}

/// The preset's base file, if it names one that does not exist (checked before any work).
std::optional<std::string> missing_base(const hs::config::DatasetConfig& cfg) {
  if (cfg.shapes.base != "file") return std::nullopt;
  if (fs::exists(cfg.shapes.base_file)) return std::nullopt;
  return cfg.shapes.base_file;
}

void run_preset(const Settings& set, const hs::config::DatasetConfig& cfg, PresetRecord& rec) {
  const auto& sc = cfg.shapes;
  const std::optional<hs::geometry::Boundary> base = hs::factory::load_base(sc);
  const int n = sc.dim == 2 ? set.grid2d : set.grid3d;
  const std::vector<double> grid = grid_points(sc.dim, n);
  const std::size_t n_grid = grid.size() / std::size_t(sc.dim);
  std::vector<double> out(n_grid);
  const double cell = std::pow(2.0 / (n - 1), sc.dim);
  for (int id = 0; id < rec.repeats; ++id) {
    auto& s = rec.seconds;
    auto& v = rec.values;
    const double c0 = cpu_seconds(), t0 = hs::core::now_seconds();
    hs::factory::ShapeSample shape;
    try {
      shape = hs::factory::make_shape(sc, base, cfg.seed, id);
    } catch (const std::runtime_error& e) {
      // Every attempt was rejected: keep the time it took and the first line of the reasons.
      const std::string what = e.what();
      s["failed_make_shape"].push_back(hs::core::now_seconds() - t0);
      v["failed_shape_id"].push_back(id);
      rec.notes.push_back(fmt::format("shape {} failed after {:.1f}s: {}", id,
                                      hs::core::now_seconds() - t0, summarise_failure(what)));
      std::cerr << fmt::format("[bench] {} shape {}/{} FAILED\n", rec.name, id + 1, rec.repeats);
      continue;
    }
    const double t_make = hs::core::now_seconds() - t0, c_make = cpu_seconds() - c0;

    const double t1 = hs::core::now_seconds();
    hs::geometry::SignedDistance sdf(shape.boundary);
    const double t_sdf_build = hs::core::now_seconds() - t1;
    sdf.evaluate(grid, out);
    const double t_sdf = hs::core::now_seconds() - t1;
    // A by-product check: the grid cells inside approximate the enclosed measure.
    const double inside = double(std::count_if(out.begin(), out.end(), [](double d) { return d < 0; }));
    const double min_sdf = *std::min_element(out.begin(), out.end());

    double t_patch = NAN, max_patch = NAN;
    if (!shape.dirichlet_facets.empty()) {
      const std::vector<std::int64_t> facets(shape.dirichlet_facets.begin(), shape.dirichlet_facets.end());
      const double t2 = hs::core::now_seconds();
      hs::geometry::FacetSetDistance patch(shape.boundary, facets);
      patch.evaluate(grid, out);
      t_patch = hs::core::now_seconds() - t2;
      max_patch = *std::max_element(out.begin(), out.end());
    }

    s["draw"].push_back(shape.seconds_draw);
    s["mesh"].push_back(shape.seconds_mesh);
    s["metrics"].push_back(shape.seconds_metrics);
    s["make_shape"].push_back(t_make);
    s["make_shape_cpu"].push_back(c_make);
    s["sdf_build"].push_back(t_sdf_build);
    s["sdf_grid"].push_back(t_sdf);
    s["patch_grid"].push_back(t_patch);
    s["total"].push_back(t_make + t_sdf + (std::isfinite(t_patch) ? t_patch : 0.0));
    v["shape_id"].push_back(id);
    v["boundary_facets"].push_back(double(shape.boundary.n_facets()));
    v["boundary_points"].push_back(double(shape.boundary.n_points()));
    v["vertices"].push_back(double(shape.mesh.n_vertices()));
    v["cells"].push_back(double(shape.mesh.n_cells()));
    v["redraws"].push_back(double(shape.rejected.size()));
    v["patch_facets"].push_back(double(shape.dirichlet_facets.size()));
    v["grid_points"].push_back(double(n_grid));
    v["measure"].push_back(shape.metrics.measure);
    v["grid_inside_measure"].push_back(inside * cell);
    v["min_signed_distance"].push_back(min_sdf);
    v["max_patch_distance"].push_back(max_patch);
    std::cerr << fmt::format("[bench] {} shape {}/{}: {} boundary facets, {} cells, {} redraws | "
                             "make_shape {} (cpu {}), SDF {}, patch {}\n",
                             rec.name, id + 1, rec.repeats, shape.boundary.n_facets(),
                             shape.mesh.n_cells(), shape.rejected.size(), fmt_time(t_make),
                             fmt_time(c_make), fmt_time(t_sdf), fmt_time(t_patch));
  }
}

json to_json(const PresetRecord& r) {
  json j;
  j["file"] = r.file;
  j["name"] = r.name;
  j["dim"] = r.dim;
  j["h"] = r.h;
  j["repeats"] = r.repeats;
  json ms = json::object(), mv = json::object(), ss = json::object(), sv = json::object();
  auto finite_or_null = [](double x) { return std::isfinite(x) ? json(x) : json(nullptr); };
  for (const auto& [k, xs] : r.seconds) {
    ms[k] = finite_or_null(median(xs));
    ss[k] = json::array();
    for (double x : xs) ss[k].push_back(finite_or_null(x));
  }
  for (const auto& [k, xs] : r.values) {
    mv[k] = finite_or_null(median(xs));
    sv[k] = json::array();
    for (double x : xs) sv[k].push_back(finite_or_null(x));
  }
  j["median_seconds"] = ms;
  j["median_values"] = mv;
  j["samples_seconds"] = ss;
  j["samples_values"] = sv;
  j["notes"] = r.notes;
  j["error"] = r.error.empty() ? json(nullptr) : json(r.error);
  return j;
}

json machine_note() {
  json m = hs::drivers::machine_note();
  m["load_average_start"] = load_average();
  return m;
}

void print_table(std::ostream& os, const std::vector<PresetRecord>& recs) {
  os << "\nPer-shape timings (median over the accepted shapes among ids 0..R-1; total = make_shape "
        "wall (with redraws) + SDF grid + patch distance)\n";
  os << fmt::format("{:<14} {:>3} {:>2} {:>4} | {:>8} {:>8} {:>8} {:>9} {:>9} {:>9} | {:>7} {:>7} {:>7} {:>7}\n",
                    "preset", "dim", "R", "fail", "draw", "mesh", "metrics", "SDF grid", "patch",
                    "total", "bfacets", "verts", "cells", "redraws");
  for (const auto& r : recs) {
    if (!r.error.empty()) {
      os << fmt::format("{:<14} {:>3} {:>2} | error: {}\n", r.name, r.dim, r.repeats, r.error);
      continue;
    }
    const auto& s = r.seconds;
    const auto& v = r.values;
    const auto f = v.find("failed_shape_id");
    const std::size_t n_failed = f == v.end() ? 0 : f->second.size();
    os << fmt::format("{:<14} {:>3} {:>2} {:>4} | {:>8} {:>8} {:>8} {:>9} {:>9} {:>9} | {:>7} {:>7} {:>7} {:>7}\n",
                      r.name, r.dim, r.repeats, n_failed, fmt_time(med(s, "draw")), fmt_time(med(s, "mesh")),
                      fmt_time(med(s, "metrics")), fmt_time(med(s, "sdf_grid")),
                      fmt_time(med(s, "patch_grid")), fmt_time(med(s, "total")),
                      fmt_count(med(v, "boundary_facets")), fmt_count(med(v, "vertices")),
                      fmt_count(med(v, "cells")), fmt_count(med(v, "redraws")));
  }
}

}  // namespace

int main(int argc, char** argv) {
  auto [ours, petsc] = hs::drivers::split_at_dashes(argc, argv);
  Settings set;
  CLI::App app{"Per-stage timings of random shapes (draw, mesh, signed-distance grid, patch "
               "distance) for dataset presets. Arguments after \"--\" go to PETSc."};
  app.add_option("presets", set.presets, "dataset configs (default: configs/presets/*.yaml)");
  app.add_option("--repeats", set.repeats, "shape ids 0..R-1 per preset (default 5 in 2D, 3 in 3D)")
      ->check(CLI::Range(1, 1000));
  app.add_option("--grid2d", set.grid2d, "2D grid nodes per axis")->check(CLI::Range(2, 4096));
  app.add_option("--grid3d", set.grid3d, "3D grid nodes per axis")->check(CLI::Range(2, 512));
  app.add_option("--json", set.json_path, "also write the results (medians + per-id values) here");
  try {
    app.parse(int(ours.size()), ours.data());
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  if (!hs::drivers::output_writable(set.json_path, "--json")) return 2;
  if (set.presets.empty()) {
    for (const char* n : {"random2d", "easy_random2d", "ood_random2d", "one_random2d", "random3d",
                          "aug_liver"})
      set.presets.push_back(fmt::format("configs/presets/{}.yaml", n));
  }

  int petsc_argc = int(petsc.size());
  char** petsc_argv = petsc.data();
  int status = 0;
  try {
    hs::core::PetscSession petsc_session(&petsc_argc, &petsc_argv, "bench_shapes\n");
    hs::mesh::GmshSession gmsh_session;
    MPI_Comm comm = PETSC_COMM_WORLD;
    if (hs::core::rank(comm) != 0) return 0;  // serial benchmark
    if (hs::core::size(comm) > 1) std::cerr << "[bench] serial benchmark: ranks > 0 idle\n";

    json out;
    out["benchmark"] = "bench_shapes";
    out["machine"] = machine_note();
    out["settings"] = {{"repeats", set.repeats ? json(set.repeats) : json("5 (2D) / 3 (3D)")},
                       {"grid2d", set.grid2d},
                       {"grid3d", set.grid3d}};
    out["presets"] = json::array();
    out["skipped"] = json::array();
    std::vector<PresetRecord> recs;
    const double t_all = hs::core::now_seconds();
    for (const auto& path : set.presets) {
      PresetRecord rec;
      rec.file = path;
      hs::config::DatasetConfig cfg;
      try {
        if (!fs::exists(path)) throw std::runtime_error("no such file");
        cfg = hs::config::parse_dataset_file(path);
      } catch (const std::exception& e) {
        std::cerr << fmt::format("[bench] skipping {}: {}\n", path, e.what());
        out["skipped"].push_back({{"file", path}, {"reason", e.what()}});
        continue;
      }
      if (auto miss = missing_base(cfg)) {
        const std::string why = "base file " + *miss + " does not exist";
        std::cerr << fmt::format("[bench] skipping {}: {}\n", path, why);
        out["skipped"].push_back({{"file", path}, {"reason", why}});
        continue;
      }
      rec.name = cfg.name;
      rec.dim = cfg.shapes.dim;
      rec.h = cfg.shapes.h;
      rec.repeats = set.repeats ? set.repeats : (rec.dim == 2 ? 5 : 3);
      rec.repeats = int(std::min<std::int64_t>(rec.repeats, cfg.n_shapes));
      if (rec.repeats < (set.repeats ? set.repeats : (rec.dim == 2 ? 5 : 3)))
        rec.notes.push_back(fmt::format("only {} shape(s) in the preset", cfg.n_shapes));
      try {
        run_preset(set, cfg, rec);
      } catch (const std::exception& e) {
        rec.error = e.what();
      }
      recs.push_back(rec);
      out["presets"].push_back(to_json(rec));
      out["total_seconds"] = hs::core::now_seconds() - t_all;
      out["machine"]["load_average_end"] = load_average();
      if (!set.json_path.empty()) hs::drivers::write_json_atomic(set.json_path, out, "--json");
    }
    out["total_seconds"] = hs::core::now_seconds() - t_all;
    out["machine"]["load_average_end"] = load_average();
    if (!set.json_path.empty()) hs::drivers::write_json_atomic(set.json_path, out, "--json");  // skips after the last run
    print_table(std::cout, recs);
    for (const auto& s : out["skipped"])
      std::cout << fmt::format("skipped {}: {}\n", s["file"].get<std::string>(),
                               s["reason"].get<std::string>());
    for (const auto& r : recs)
      for (const auto& n : r.notes) std::cout << fmt::format("{}: {}\n", r.name, n);
    std::cout << fmt::format("\ntotal {:.1f}s on {} ({} cores), load average {} -> {}\n",
                             hs::core::now_seconds() - t_all,
                             out["machine"]["hostname"].get<std::string>(),
                             out["machine"]["nproc"].get<long>(),
                             out["machine"]["load_average_start"].get<std::string>(),
                             load_average());
  } catch (const std::exception& e) {
    std::cerr << fmt::format("error: {}\n", e.what());
    status = 1;
  }
  return status;
}
