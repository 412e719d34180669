#include "hypershape/study/bench_shapes.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>

#include "hypershape/config/dataset.hpp"
#include "hypershape/core/timer.hpp"
#include "hypershape/factory/shape_pipeline.hpp"
#include "hypershape/geometry/distance.hpp"
#include "hypershape/study/machine.hpp"
#include "hypershape/study/output.hpp"
#include "hypershape/study/stats.hpp"
#include "hypershape/study/timing.hpp"

namespace hypershape::study {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

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

double med(const std::map<std::string, std::vector<double>>& m, const std::string& k) {
  auto it = m.find(k);
  return it == m.end() ? NAN : median(it->second);
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
std::optional<std::string> missing_base(const config::DatasetConfig& cfg) {
  if (cfg.shapes.base != "file") return std::nullopt;
  if (fs::exists(cfg.shapes.base_file)) return std::nullopt;
  return cfg.shapes.base_file;
}

/// The evaluation grid of a preset and the buffer for its distances.
struct Grid {
  std::vector<double> points, out;
  std::size_t n_points = 0;
  double cell = 0;  ///< measure of a grid cell
};

/// Signed-distance and patch-distance grids of an accepted shape, timed and recorded.
void measure_distances(const factory::ShapeSample& shape, Grid& g, double t_make, PresetRecord& rec) {
  auto& s = rec.seconds;
  auto& v = rec.values;
  const double t1 = core::now_seconds();
  geometry::SignedDistance sdf(shape.boundary);
  const double t_sdf_build = core::now_seconds() - t1;
  sdf.evaluate(g.points, g.out);
  const double t_sdf = core::now_seconds() - t1;
  // A by-product check: the grid cells inside approximate the enclosed measure.
  const double inside = double(std::count_if(g.out.begin(), g.out.end(), [](double d) { return d < 0; }));
  const double min_sdf = *std::min_element(g.out.begin(), g.out.end());

  double t_patch = NAN, max_patch = NAN;
  if (!shape.dirichlet_facets.empty()) {
    const std::vector<std::int64_t> facets(shape.dirichlet_facets.begin(), shape.dirichlet_facets.end());
    const double t2 = core::now_seconds();
    geometry::FacetSetDistance patch(shape.boundary, facets);
    patch.evaluate(g.points, g.out);
    t_patch = core::now_seconds() - t2;
    max_patch = *std::max_element(g.out.begin(), g.out.end());
  }
  s["sdf_build"].push_back(t_sdf_build);
  s["sdf_grid"].push_back(t_sdf);
  s["patch_grid"].push_back(t_patch);
  s["total"].push_back(t_make + t_sdf + (std::isfinite(t_patch) ? t_patch : 0.0));
  v["grid_points"].push_back(double(g.n_points));
  v["measure"].push_back(shape.metrics.measure);
  v["grid_inside_measure"].push_back(inside * g.cell);
  v["min_signed_distance"].push_back(min_sdf);
  v["max_patch_distance"].push_back(max_patch);
}

/// The library's own timings and the sizes of an accepted shape.
void record_shape(const factory::ShapeSample& shape, int id, double t_make, double c_make, PresetRecord& rec) {
  auto& s = rec.seconds;
  auto& v = rec.values;
  s["draw"].push_back(shape.seconds_draw);
  s["mesh"].push_back(shape.seconds_mesh);
  s["metrics"].push_back(shape.seconds_metrics);
  s["make_shape"].push_back(t_make);
  s["make_shape_cpu"].push_back(c_make);
  v["shape_id"].push_back(id);
  v["boundary_facets"].push_back(double(shape.boundary.n_facets()));
  v["boundary_points"].push_back(double(shape.boundary.n_points()));
  v["vertices"].push_back(double(shape.mesh.n_vertices()));
  v["cells"].push_back(double(shape.mesh.n_cells()));
  v["redraws"].push_back(double(shape.rejected.size()));
  v["patch_facets"].push_back(double(shape.dirichlet_facets.size()));
}

void run_preset(const ShapeBenchOptions& set, const config::DatasetConfig& cfg, PresetRecord& rec) {
  const auto& sc = cfg.shapes;
  const std::optional<geometry::Boundary> base = factory::load_base(sc);
  const int n = sc.dim == 2 ? set.grid2d : set.grid3d;
  Grid g;
  g.points = grid_points(sc.dim, n);
  g.n_points = g.points.size() / std::size_t(sc.dim);
  g.out.resize(g.n_points);
  g.cell = std::pow(2.0 / (n - 1), sc.dim);
  for (int id = 0; id < rec.repeats; ++id) {
    const double c0 = cpu_seconds(), t0 = core::now_seconds();
    factory::ShapeSample shape;
    try {
      shape = factory::make_shape(sc, base, cfg.seed, id);
    } catch (const std::runtime_error& e) {
      // Every attempt was rejected: keep the time it took and the first line of the reasons.
      const std::string what = e.what();
      rec.seconds["failed_make_shape"].push_back(core::now_seconds() - t0);
      rec.values["failed_shape_id"].push_back(id);
      rec.notes.push_back(fmt::format("shape {} failed after {:.1f}s: {}", id, core::now_seconds() - t0,
                                      summarise_failure(what)));
      std::cerr << fmt::format("[bench] {} shape {}/{} FAILED\n", rec.name, id + 1, rec.repeats);
      continue;
    }
    const double t_make = core::now_seconds() - t0, c_make = cpu_seconds() - c0;
    measure_distances(shape, g, t_make, rec);
    record_shape(shape, id, t_make, c_make, rec);
    std::cerr << fmt::format("[bench] {} shape {}/{}: {} boundary facets, {} cells, {} redraws | "
                             "make_shape {} (cpu {}), SDF {}, patch {}\n",
                             rec.name, id + 1, rec.repeats, shape.boundary.n_facets(), shape.mesh.n_cells(),
                             shape.rejected.size(), format_seconds(t_make), format_seconds(c_make),
                             format_seconds(rec.seconds["sdf_grid"].back()),
                             format_seconds(rec.seconds["patch_grid"].back()));
  }
}

json to_json(const PresetRecord& r) {
  json j{{"file", r.file}, {"name", r.name}, {"dim", r.dim}, {"h", r.h}, {"repeats", r.repeats}};
  json ms = json::object(), mv = json::object(), ss = json::object(), sv = json::object();
  for (const auto& [k, xs] : r.seconds) {
    ms[k] = number_or_null(median(xs));
    ss[k] = numbers_or_null(xs);
  }
  for (const auto& [k, xs] : r.values) {
    mv[k] = number_or_null(median(xs));
    sv[k] = numbers_or_null(xs);
  }
  j["median_seconds"] = ms;
  j["median_values"] = mv;
  j["samples_seconds"] = ss;
  j["samples_values"] = sv;
  j["notes"] = r.notes;
  j["error"] = r.error.empty() ? json(nullptr) : json(r.error);
  return j;
}

void print_table(std::ostream& os, const std::vector<PresetRecord>& recs) {
  os << "\nPer-shape timings (median over the accepted shapes among ids 0..R-1; total = make_shape "
        "wall (with redraws) + SDF grid + patch distance)\n";
  os << fmt::format("{:<14} {:>3} {:>2} {:>4} | {:>8} {:>8} {:>8} {:>9} {:>9} {:>9} | {:>7} {:>7} {:>7} {:>7}\n",
                    "preset", "dim", "R", "fail", "draw", "mesh", "metrics", "SDF grid", "patch", "total", "bfacets",
                    "verts", "cells", "redraws");
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
                      r.name, r.dim, r.repeats, n_failed, format_seconds(med(s, "draw")),
                      format_seconds(med(s, "mesh")), format_seconds(med(s, "metrics")),
                      format_seconds(med(s, "sdf_grid")), format_seconds(med(s, "patch_grid")),
                      format_seconds(med(s, "total")), format_count(med(v, "boundary_facets")),
                      format_count(med(v, "vertices")), format_count(med(v, "cells")), format_count(med(v, "redraws")));
  }
}

/// The preset at `path`, or nullopt after recording why it is skipped in out["skipped"].
std::optional<config::DatasetConfig> read_preset(const std::string& path, json& out) {
  std::string why;
  try {
    if (!fs::exists(path)) throw std::runtime_error("no such file");
    auto cfg = config::parse_dataset_file(path);
    if (auto miss = missing_base(cfg)) {
      why = "base file " + *miss + " does not exist";
    } else {
      return cfg;
    }
  } catch (const std::exception& e) {
    why = e.what();
  }
  std::cerr << fmt::format("[bench] skipping {}: {}\n", path, why);
  out["skipped"].push_back({{"file", path}, {"reason", why}});
  return std::nullopt;
}

PresetRecord bench_preset(const ShapeBenchOptions& set, const std::string& path, const config::DatasetConfig& cfg) {
  PresetRecord rec;
  rec.file = path;
  rec.name = cfg.name;
  rec.dim = cfg.shapes.dim;
  rec.h = cfg.shapes.h;
  const int wanted = set.repeats ? set.repeats : (rec.dim == 2 ? 5 : 3);
  rec.repeats = int(std::min<std::int64_t>(wanted, cfg.n_shapes));
  if (rec.repeats < wanted) rec.notes.push_back(fmt::format("only {} shape(s) in the preset", cfg.n_shapes));
  try {
    run_preset(set, cfg, rec);
  } catch (const std::exception& e) {
    rec.error = e.what();
  }
  return rec;
}

json start_output(const ShapeBenchOptions& set) {
  json out;
  out["benchmark"] = "bench_shapes";
  out["machine"] = machine_note();
  out["machine"]["load_average_start"] = load_average_text();
  out["settings"] = {{"repeats", set.repeats ? json(set.repeats) : json("5 (2D) / 3 (3D)")},
                     {"grid2d", set.grid2d},
                     {"grid3d", set.grid3d}};
  out["presets"] = json::array();
  out["skipped"] = json::array();
  return out;
}

}  // namespace

void run_shape_bench(const ShapeBenchOptions& set, std::ostream& table) {
  json out = start_output(set);
  std::vector<PresetRecord> recs;
  const double t_all = core::now_seconds();
  auto save = [&] {
    out["total_seconds"] = core::now_seconds() - t_all;
    out["machine"]["load_average_end"] = load_average_text();
    if (!set.json_path.empty()) write_json_atomic(set.json_path, out, "--json");
  };
  for (const auto& path : set.presets) {
    const auto cfg = read_preset(path, out);
    if (!cfg) continue;
    recs.push_back(bench_preset(set, path, *cfg));
    out["presets"].push_back(to_json(recs.back()));
    save();
  }
  save();  // skips after the last run
  print_table(table, recs);
  for (const auto& s : out["skipped"])
    table << fmt::format("skipped {}: {}\n", s["file"].get<std::string>(), s["reason"].get<std::string>());
  for (const auto& r : recs)
    for (const auto& n : r.notes) table << fmt::format("{}: {}\n", r.name, n);
  table << fmt::format("\ntotal {:.1f}s on {} ({} cores), load average {} -> {}\n", core::now_seconds() - t_all,
                       out["machine"]["hostname"].get<std::string>(), out["machine"]["nproc"].get<long>(),
                       out["machine"]["load_average_start"].get<std::string>(), load_average_text());
}

}  // namespace hypershape::study
