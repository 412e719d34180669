#pragma once
/// XDMF views of dataset shards for ParaView (its default Xdmf3ReaderS and the legacy XDMF
/// reader) and meshio: every shape of a shard, with its per-node fields, and every load case of
/// it as a time step (displacement, traction). Per-load-case fields are (L x n x c) arrays in the
/// shard; readers that take no HyperSlab need one (n x c) dataset per load case, so a small
/// companion file beside the XDMF holds an HDF5 virtual dataset per field and load case that maps
/// row l of the shard's array (no data copied; the shard is not touched).
#include <string>

namespace hypershape::io {

/// Writes, for the complete shard `shard_path`, into the directory of `xdmf_path`:
///   `xdmf_path` (e.g. xdmf/shard-000000.xdmf)  a spatial collection of the shard's solved shapes,
///                                              each a temporal collection (load case l = time l);
///   the same name with `.h5`                   the companion file: /shapes/<id>/<field>/<l>, an
///                                              (n x c) virtual dataset of the shard's
///                                              /shapes/<id>/loads/<field>[l] (relative path);
///   `shape-<id>.xdmf` per solved shape         that shape's temporal collection alone (what
///                                              meshio's TimeSeriesReader reads).
/// Each file is written under a temporary name and renamed. Not collective. Throws
/// std::runtime_error if the shard cannot be read or a file cannot be written.
void write_dataset_xdmf(const std::string& shard_path, const std::string& xdmf_path);

}  // namespace hypershape::io
