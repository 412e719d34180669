#pragma once
/// The index step: turns the shards in a dataset directory into one dataset. Reads only the
/// shards' headers and per-shape summaries (never the big arrays), so it is quick.
///   manifest.json  every shard (shapes, load cases by status, bytes, CRC-32), totals, missing
///                  shards, failed shapes
///   splits.json    train / val / test shape ids: a seeded permutation of all ids cut by the
///                  config's fractions (shapes that failed are left out of every split)
///   stats.json     normalisation statistics per field and component (count, mean, std, rms)
///                  over the train split only
///   xdmf/shard-NNNNNN.xdmf   ParaView views of every shape and load case
/// splits.json and stats.json are written only when no shard is missing. Files appear
/// atomically. Run by `generate` when it finds the dataset complete, or as
/// `hypershape index DIR` after a SLURM array.
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace hypershape::factory {

struct IndexReport {
  std::int64_t shards = 0;
  std::vector<std::int64_t> missing_shards;
  std::int64_t shapes_ok = 0, shapes_failed = 0, loads_ok = 0, loads_failed = 0;
  /// The shards by the numerics platform that wrote them (core::numerics_platform; "" for shards
  /// of builds before 2026-11-28, which are not counted as a kind).
  std::map<std::string, std::vector<std::int64_t>> numerics;
  /// More than one known platform: the data are not bit for bit what one machine makes.
  bool mixed_numerics() const;
  /// The warning `index` prints (and manifest.json's `numerics_platforms`) then; else "".
  std::string mixed_numerics_warning() const;
  bool complete() const { return missing_shards.empty(); }
};

/// Not collective. Throws core::InputError if `dir` holds no dataset (dataset.yaml) and
/// std::runtime_error for a damaged shard.
IndexReport index_dataset(const std::string& dir);

}  // namespace hypershape::factory
