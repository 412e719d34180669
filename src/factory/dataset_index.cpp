#include "hypershape/factory/dataset_index.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <numeric>

#include "hypershape/config/dataset.hpp"
#include "hypershape/core/input_error.hpp"
#include "hypershape/core/random.hpp"
#include "hypershape/factory/generate.hpp"
#include "hypershape/factory/shard_record.hpp"
#include "hypershape/io/dataset_shard.hpp"
#include "hypershape/io/dataset_xdmf.hpp"
#include "text_file.hpp"

namespace hypershape::factory {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

void write_json(const fs::path& path, const json& j) { detail::write_atomically(path, j.dump(1) + "\n"); }

/// Shape ids [0, n) cut into train / val / test by a seeded permutation.
std::map<std::string, std::vector<std::int64_t>> make_splits(const config::DatasetConfig& c) {
  const std::int64_t n = c.n_shapes;
  std::vector<std::int64_t> ids(static_cast<std::size_t>(n));
  std::iota(ids.begin(), ids.end(), 0);
  core::RandomStream rng(c.seed, core::Purpose::split, {});
  for (std::int64_t i = n - 1; i > 0; --i) {
    const auto j = std::min<std::int64_t>(i, std::int64_t(rng.uniform() * double(i + 1)));
    std::swap(ids[std::size_t(i)], ids[std::size_t(j)]);
  }
  const auto n_train = std::int64_t(std::llround(c.split.train * double(n)));
  const auto n_val = std::min<std::int64_t>(n - n_train, std::llround(c.split.val * double(n)));
  std::map<std::string, std::vector<std::int64_t>> out;
  out["train"].assign(ids.begin(), ids.begin() + n_train);
  out["val"].assign(ids.begin() + n_train, ids.begin() + n_train + n_val);
  out["test"].assign(ids.begin() + n_train + n_val, ids.end());
  for (auto& [k, v] : out) std::sort(v.begin(), v.end());
  return out;
}

/// One shard's manifest entry; its counts added to `rep`, its failed shapes to `failed_shapes`.
json shard_entry(std::int64_t k, const fs::path& p, const io::ShardSummary& s, IndexReport& rep,
                 std::vector<std::int64_t>& failed_shapes) {
  std::int64_t ok = 0, failed = 0, lok = 0, lfailed = 0;
  for (const auto& sh : s.shapes) {
    (sh.ok ? ok : failed) += 1;
    lok += sh.loads_ok;
    lfailed += sh.loads_failed;
    if (!sh.ok) failed_shapes.push_back(sh.shape_id);
  }
  rep.shapes_ok += ok;
  rep.shapes_failed += failed;
  rep.loads_ok += lok;
  rep.loads_failed += lfailed;
  return {{"file", "shards/" + shard_name(k)},
          {"index", k},
          {"first_shape", s.header.first_shape},
          {"n_shapes", s.header.n_shapes},
          {"shapes_ok", ok},
          {"shapes_failed", failed},
          {"load_cases_converged", lok},
          {"load_cases_failed", lfailed},
          {"bytes", std::int64_t(fs::file_size(p))},
          {"crc32", fmt::format("{:08x}", io::file_crc32(p.string()))}};
}

json manifest_json(const config::DatasetConfig& cfg, const std::string& hash, const IndexReport& rep,
                   const std::vector<std::int64_t>& failed_shapes, json shards) {
  return {{"format", "hypershape-dataset"},
          {"format_version", io::dataset_format_version},
          {"name", cfg.name},
          {"config_hash", hash},
          {"dim", cfg.shapes.dim},
          {"n_shapes", cfg.n_shapes},
          {"load_cases_per_shape", cfg.loads.count},
          {"shard_size", cfg.shard_size},
          {"complete", rep.complete()},
          {"missing_shards", rep.missing_shards},
          {"failed_shapes", failed_shapes},
          {"totals",
           {{"shapes_ok", rep.shapes_ok},
            {"shapes_failed", rep.shapes_failed},
            {"load_cases_converged", rep.loads_ok},
            {"load_cases_failed", rep.loads_failed}}},
          {"shards", std::move(shards)}};
}

}  // namespace

bool IndexReport::mixed_numerics() const {
  return std::count_if(numerics.begin(), numerics.end(), [](const auto& p) { return !p.first.empty(); }) > 1;
}

std::string IndexReport::mixed_numerics_warning() const {
  if (!mixed_numerics()) return "";
  std::string kinds;
  for (const auto& [platform, ks] : numerics)
    if (!platform.empty()) kinds += fmt::format("\n  {} shard(s) from \"{}\" (first: {})", ks.size(), platform, ks.front());
  return "warning: the shards were written on machines of different kinds:" + kinds +
         "\n  the dataset is valid, but not bit for bit what one machine makes (labels agree to round-off, "
         "a shape may mesh differently); README, \"On machines of different kinds\"";
}

namespace {

using ShapesById = std::map<std::int64_t, const io::ShardSummary::Shape*>;

/// splits.json: the seeded split of the shape ids, failed shapes in none. Returns the splits.
std::map<std::string, std::vector<std::int64_t>> write_splits(const fs::path& root, const config::DatasetConfig& cfg,
                                                              const ShapesById& by_id) {
  auto splits = make_splits(cfg);
  json js = {{"seed", cfg.seed},
             {"fractions", {{"train", cfg.split.train}, {"val", cfg.split.val}, {"test", cfg.split.test}}}};
  for (auto& [name, ids] : splits) {
    std::vector<std::int64_t> kept;
    for (auto id : ids)
      if (by_id.count(id) && by_id.at(id)->ok) kept.push_back(id);
    js[name] = kept;
    ids = kept;
  }
  write_json(root / "splits.json", js);
  return splits;
}

/// stats.json: normalisation statistics over the train split (fixed order: shape id).
void write_stats(const fs::path& root, const std::vector<std::int64_t>& train, const ShapesById& by_id) {
  std::map<std::string, std::vector<double>> sums;
  for (auto id : train)
    for (const auto& [field, rows] : by_id.at(id)->stats) {
      auto& acc = sums[field];
      acc.resize(rows.size(), 0.0);
      for (std::size_t i = 0; i < rows.size(); ++i) acc[i] += rows[i];
    }
  json stats = json::object();
  for (const auto& [field, acc] : sums) {
    std::vector<double> mean, stdev, rms, count;
    for (std::size_t c = 0; c + 2 < acc.size(); c += 3) {
      const double n = acc[c], m = n > 0 ? acc[c + 1] / n : 0, q = n > 0 ? acc[c + 2] / n : 0;
      count.push_back(n);
      mean.push_back(m);
      stdev.push_back(std::sqrt(std::max(0.0, q - m * m)));
      rms.push_back(std::sqrt(std::max(0.0, q)));
    }
    stats[field] = {{"count", count}, {"mean", mean}, {"std", stdev}, {"rms", rms}};
  }
  write_json(root / "stats.json", {{"split", "train"}, {"n_shapes", train.size()}, {"fields", stats}});
}

}  // namespace

IndexReport index_dataset(const std::string& dir) {
  const fs::path root(dir);
  const fs::path yaml = root / "dataset.yaml";
  if (!fs::exists(yaml)) throw core::InputError(dir, "", "not a dataset directory (no dataset.yaml)");
  const config::DatasetConfig cfg = config::parse_dataset_file(yaml.string());
  // The shards carry the digest of the dataset's meaning (config::canonical_text).
  const std::string hash = config_hash(cfg);
  IndexReport rep;
  rep.shards = (cfg.n_shapes + cfg.shard_size - 1) / cfg.shard_size;
  json shards = json::array();
  std::vector<std::int64_t> failed_shapes;
  std::vector<io::ShardSummary> summaries;
  summaries.reserve(std::size_t(rep.shards));
  for (std::int64_t k = 0; k < rep.shards; ++k) {
    const fs::path p = root / "shards" / shard_name(k);
    if (!fs::exists(p)) {
      rep.missing_shards.push_back(k);
      continue;
    }
    if (const auto problem = shard_problem(dir, shard_identity(cfg, hash, k)); !problem.empty())
      throw std::runtime_error(p.string() + ": " + problem + "; run `hypershape generate` on this directory "
                               "with its config again: it redoes the shard");
    summaries.push_back(io::read_shard_summary(p.string()));
    const auto& sw = summaries.back().header.software;
    const auto numerics = sw.find("numerics");
    rep.numerics[numerics == sw.end() ? "" : numerics->second].push_back(k);
    shards.push_back(shard_entry(k, p, summaries.back(), rep, failed_shapes));
  }
  json manifest = manifest_json(cfg, hash, rep, failed_shapes, std::move(shards));
  if (rep.mixed_numerics()) manifest["numerics_platforms"] = rep.numerics;  // (one kind: not written)
  write_json(root / "manifest.json", manifest);
  if (const std::string w = rep.mixed_numerics_warning(); !w.empty()) std::cerr << w << "\n";
  if (!rep.complete()) return rep;
  ShapesById by_id;
  for (const auto& s : summaries)
    for (const auto& sh : s.shapes) by_id[sh.shape_id] = &sh;
  const auto splits = write_splits(root, cfg, by_id);
  write_stats(root, splits.at("train"), by_id);
  fs::create_directories(root / "xdmf");
  for (std::int64_t k = 0; k < rep.shards; ++k)
    io::write_dataset_xdmf((root / "shards" / shard_name(k)).string(),
                           (root / "xdmf" / fmt::format("shard-{:06d}.xdmf", k)).string());
  return rep;
}

}  // namespace hypershape::factory
