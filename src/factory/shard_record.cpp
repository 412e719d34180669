#include "hypershape/factory/shard_record.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <filesystem>

#include "hypershape/factory/generate.hpp"
#include "hypershape/io/dataset_shard.hpp"
#include "text_file.hpp"

namespace hypershape::factory {

namespace fs = std::filesystem;

std::string config_hash(const config::DatasetConfig& cfg) { return io::text_digest(config::canonical_text(cfg)); }

std::int64_t shapes_in_shard(const config::DatasetConfig& cfg, std::int64_t k) {
  return std::min<std::int64_t>(cfg.shard_size, cfg.n_shapes - k * cfg.shard_size);
}

ShardIdentity shard_identity(const config::DatasetConfig& cfg, const std::string& hash, std::int64_t k) {
  return {hash, k, k * cfg.shard_size, shapes_in_shard(cfg, k), cfg.loads.count};
}

std::string record_path(const std::string& dir, std::int64_t k) {
  return (fs::path(dir) / "records" / fmt::format("shard-{:06d}.json", k)).string();
}

void write_shard_record(const std::string& dir, const ShardIdentity& id, std::uint32_t crc32, std::uint64_t bytes) {
  fs::create_directories(fs::path(dir) / "records");
  const nlohmann::json j = {{"shard", id.index},        {"config_hash", id.config_hash},
                            {"first_shape", id.first_shape}, {"n_shapes", id.n_shapes},
                            {"crc32", fmt::format("{:08x}", crc32)}, {"bytes", bytes}};
  try {
    detail::write_atomically(record_path(dir, id.index), j.dump() + "\n");
  } catch (const std::exception& e) {  // a full disk right after the shard: resumable as any
    throw io::StorageError(fmt::format("{}; shard {} is written, its record not: the shards before it are complete, "
                                       "run the same command again to resume",
                                       e.what(), id.index));
  }
}

namespace {

/// The record's complaint about the file's bytes, or "".
std::string bytes_problem(const std::string& dir, const ShardIdentity& id, const std::string& file) {
  nlohmann::json r;
  try {
    r = nlohmann::json::parse(detail::read_text(record_path(dir, id.index)));
  } catch (const std::exception&) {
    return "no readable record of its checksum (" + record_path(dir, id.index) +
           "; written by an interrupted or older run)";
  }
  if (r.value("config_hash", "") != id.config_hash || r.value("shard", std::int64_t(-1)) != id.index)
    return "its record belongs to another dataset or shard";
  const auto bytes = std::uint64_t(fs::file_size(file));
  const std::string crc = fmt::format("{:08x}", io::file_crc32(file));
  if (bytes != r.value("bytes", std::uint64_t(0)) || crc != r.value("crc32", ""))
    return fmt::format("damaged: {} bytes with CRC-32 {}, recorded {} bytes with CRC-32 {}", bytes, crc,
                       r.value("bytes", std::uint64_t(0)), r.value("crc32", "?"));
  return "";
}

}  // namespace

std::string shard_problem(const std::string& dir, const ShardIdentity& id) {
  const std::string file = (fs::path(dir) / "shards" / shard_name(id.index)).string();
  if (auto p = bytes_problem(dir, id, file); !p.empty()) return p;
  io::ShardHeader h;
  try {
    h = io::read_shard_header(file);
  } catch (const std::exception& e) {
    return e.what();
  }
  if (h.config_hash != id.config_hash) return "belongs to another dataset (config_hash " + h.config_hash + ")";
  if (h.shard_index != id.index || h.first_shape != id.first_shape || h.n_shapes != id.n_shapes ||
      h.n_loads != id.n_loads)
    return fmt::format("holds shard {} (shapes {}..{}, {} load cases), not shard {} (shapes {}..{}, {})",
                       h.shard_index, h.first_shape, h.first_shape + h.n_shapes - 1, h.n_loads, id.index,
                       id.first_shape, id.first_shape + id.n_shapes - 1, id.n_loads);
  return "";
}

}  // namespace hypershape::factory
