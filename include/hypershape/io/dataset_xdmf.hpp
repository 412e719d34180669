#pragma once
/// XDMF views of dataset shards for ParaView: every shape of a shard, with its per-node fields,
/// and every load case of it as a time step (displacement, traction). The XDMF file refers to
/// the arrays in the shard by relative path; nothing is copied.
#include <string>

namespace hypershape::io {

/// Writes `xdmf_path` describing the complete shard `shard_path` (atomically: temporary name,
/// then rename). Not collective. Throws std::runtime_error if the shard cannot be read.
void write_dataset_xdmf(const std::string& shard_path, const std::string& xdmf_path);

}  // namespace hypershape::io
