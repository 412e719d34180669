#pragma once
/// Dataset shards: one HDF5 file per block of `shard_size` consecutive shapes, the unit of work,
/// of output and of resume. A shard is written under a temporary name and renamed into place
/// only once complete and synced, so a shard on disk is either whole or absent (FACTS.md: a
/// kill while growing one HDF5 file lost the file). The layout is in docs/FORMAT.md.
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

#include "hypershape/io/shape_file.hpp"

namespace hypershape::io {

inline constexpr int dataset_format_version = 1;

/// A named array of a shape (path relative to the shape's group, e.g. "loads/displacement").
/// Arrays under "loads/" with two or more dimensions are chunked one load case per chunk.
struct Array {
  std::string name;
  std::vector<std::uint64_t> shape;
  std::variant<std::vector<double>, std::vector<float>, std::vector<std::int64_t>,
               std::vector<std::int8_t>>
      data;
  std::string meaning;  ///< attribute "meaning"
  std::string units;    ///< attribute "units" (empty: none)
};

/// Everything a shard holds about one shape.
struct ShardShape {
  ShapeRecord shape;     ///< geometry as in shape sets (only id/numbers/rejected if it failed)
  bool ok = true;        ///< false: no acceptable draw; nothing was solved
  std::string failure;   ///< why, when !ok
  std::vector<Array> arrays;
  std::vector<std::string> load_reasons;  ///< "loads/reason", one per load case
};

struct ShardHeader {
  std::string dataset_name;
  std::string config_text;    ///< the resolved config
  std::string scene_text;     ///< the effects solved (YAML, draws as written), dataset "scene"
  std::string config_hash;    ///< hex digest of config_text: shards of one dataset agree
  std::uint64_t seed = 0;
  int dim = 2;
  std::int64_t shard_index = 0, first_shape = 0, n_shapes = 0;
  int n_loads = 0;            ///< load cases per shape
  /// Software versions ("petsc", "gmsh", ...); "hypershape" and "hdf5" are added on write.
  std::map<std::string, std::string> software;
};

/// A shard could not be written (a full disk, an I/O error). Its temporary file is gone, but
/// HDF5 1.10.8 may still hold the file and crash at library shutdown (measured: exit 139 in
/// H5F__close_cb after a failed flush), so a driver ends the process without HDF5's shutdown.
class StorageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Writes one shard: add() each shape in order, then commit(). Destroying an uncommitted
/// writer removes the temporary file. A failed write (a full disk) removes it too and throws
/// StorageError naming the file and the free space; HDF5 prints nothing. Not collective.
class ShardWriter {
 public:
  /// Creates `path` + ".tmp" (truncating a stale one). Throws std::runtime_error.
  ShardWriter(std::string path, const ShardHeader& header);
  ~ShardWriter();
  ShardWriter(const ShardWriter&) = delete;
  ShardWriter& operator=(const ShardWriter&) = delete;
  void add(const ShardShape& shape);
  /// Marks the shard complete, closes and fsyncs it, calls `before_rename(crc32, bytes)` of
  /// the finished file (to record its checksum), and renames it to `path`.
  void commit(const std::function<void(std::uint32_t crc32, std::uint64_t bytes)>& before_rename = {});

 private:
  void write_header(const ShardHeader& header);
  void add_shape(const ShardShape& shape);
  void close_file();
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// What the index step needs of a shard, without the big arrays.
struct ShardSummary {
  ShardHeader header;
  struct Shape {
    std::int64_t shape_id = 0;
    bool ok = false;
    int loads_ok = 0, loads_failed = 0;
    /// "stats/<field>": per component rows of (count, sum, sum of squares).
    std::map<std::string, std::vector<double>> stats;
  };
  std::vector<Shape> shapes;
};

/// Reads the header and the per-shape summaries. Throws std::runtime_error if the file is not
/// a complete shard of this format.
ShardSummary read_shard_summary(const std::string& path);
/// Reads the header attributes only (config_text not read). Throws std::runtime_error if the
/// file is not a complete shard of this format; HDF5 prints nothing.
ShardHeader read_shard_header(const std::string& path);
/// CRC-32 (zlib) of a file's bytes.
std::uint32_t file_crc32(const std::string& path);
/// A stable 64-bit digest (hex) of a text (FNV-1a), for config identity.
std::string text_digest(const std::string& text);

}  // namespace hypershape::io
