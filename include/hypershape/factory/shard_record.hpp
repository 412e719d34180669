#pragma once
/// What makes a shard on disk trustworthy on resume: its record, `DIR/records/shard-NNNNNN.json`
/// (the CRC-32 and size of the file, the dataset's config hash, the shard's index and shapes),
/// written when the shard is complete and before it is renamed into place. A resume keeps a
/// shard only if the file's bytes match its record and its header matches what shard k of this
/// dataset must be; anything else (damaged bytes, a shard copied over another, one of another
/// dataset, no record) is redone.
#include <cstdint>
#include <string>

#include "hypershape/config/dataset.hpp"

namespace hypershape::factory {

/// What shard k of a dataset must be.
struct ShardIdentity {
  std::string config_hash;
  std::int64_t index = 0, first_shape = 0, n_shapes = 0;
  int n_loads = 0;
};

/// The dataset's identity: the digest of config::canonical_text (its meaning, not its text).
std::string config_hash(const config::DatasetConfig& cfg);
/// Number of shapes of shard k (the last one may be short).
std::int64_t shapes_in_shard(const config::DatasetConfig& cfg, std::int64_t k);
/// What shard k of this dataset must be.
ShardIdentity shard_identity(const config::DatasetConfig& cfg, const std::string& hash, std::int64_t k);

/// DIR/records/shard-NNNNNN.json.
std::string record_path(const std::string& dir, std::int64_t k);
/// Writes the record atomically (creates DIR/records). Not collective.
void write_shard_record(const std::string& dir, const ShardIdentity& id, std::uint32_t crc32, std::uint64_t bytes);
/// Why the existing shard file of `id` cannot be kept; empty if it is verified (bytes against
/// the record, header against `id`). Reads the whole file once. Not collective.
std::string shard_problem(const std::string& dir, const ShardIdentity& id);

}  // namespace hypershape::factory
