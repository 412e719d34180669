#include "hypershape/io/dataset_shard.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <hdf5.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <numeric>

#include "chunk_deflate.hpp"
#include "h5_util.hpp"
#include "hypershape/core/interrupt.hpp"
#include "shape_group.hpp"

namespace hypershape::io {

namespace {

namespace fs = std::filesystem;

Id make_group(hid_t parent, const std::string& name) {
  Id gcpl = untimed(H5P_GROUP_CREATE);
  Id lcpl{check_id(H5Pcreate(H5P_LINK_CREATE), name), H5Pclose};
  check(H5Pset_create_intermediate_group(lcpl.id, 1), name);
  return {check_id(H5Gcreate2(parent, name.c_str(), lcpl.id, gcpl.id, H5P_DEFAULT), name), H5Gclose};
}

void write_array(hid_t g, const Array& a) {
  const int rank = int(a.shape.size());
  std::vector<hsize_t> dims(a.shape.begin(), a.shape.end());
  const hsize_t n = std::accumulate(dims.begin(), dims.end(), hsize_t(1), std::multiplies<>());
  hid_t type = -1;
  const void* data = nullptr;
  std::size_t size = 0, elem = 0;
  std::visit(
      [&](const auto& v) {
        using T = typename std::decay_t<decltype(v)>::value_type;
        data = v.data();
        size = v.size();
        elem = sizeof(T);
        if constexpr (std::is_same_v<T, double>) type = H5T_NATIVE_DOUBLE;
        else if constexpr (std::is_same_v<T, float>) type = H5T_NATIVE_FLOAT;
        else if constexpr (std::is_same_v<T, std::int64_t>) type = H5T_NATIVE_INT64;
        else type = H5T_NATIVE_INT8;
      },
      a.data);
  if (size != n) throw std::runtime_error(fmt::format("array {}: {} values for shape of {}", a.name, size, n));
  Id space{check_id(H5Screate_simple(rank, dims.data(), nullptr), a.name), H5Sclose};
  Id dcpl = untimed(H5P_DATASET_CREATE);
  std::vector<hsize_t> chunk = dims;
  if (n > 0) {
    if (a.name.rfind("loads/", 0) == 0 && rank >= 2) {
      chunk[0] = 1;  // one load case per chunk: a training sample reads one chunk
    } else {
      const hsize_t rest = rank > 1 ? n / dims[0] : 1;
      chunk[0] = std::clamp<hsize_t>((1u << 20) / std::max<hsize_t>(1, rest * elem / 4), 1, dims[0]);
    }
    declare_deflated_chunks(dcpl.id, chunk, a.name);
  }
  Id lcpl{check_id(H5Pcreate(H5P_LINK_CREATE), a.name), H5Pclose};
  check(H5Pset_create_intermediate_group(lcpl.id, 1), a.name);
  Id ds{check_id(H5Dcreate2(g, a.name.c_str(), type, space.id, lcpl.id, dcpl.id, H5P_DEFAULT), a.name), H5Dclose};
  if (n > 0) write_deflated_chunks(ds.id, data, dims, chunk, elem);
  if (!a.meaning.empty()) attr_string(ds.id, "meaning", a.meaning);
  if (!a.units.empty()) attr_string(ds.id, "units", a.units);
}

void write_strings(hid_t g, const char* name, const std::vector<std::string>& v) {
  Id type{check_id(H5Tcopy(H5T_C_S1), name), H5Tclose};
  check(H5Tset_size(type.id, H5T_VARIABLE), name);
  check(H5Tset_cset(type.id, H5T_CSET_UTF8), name);
  hsize_t dims[1] = {v.size()};
  Id space{check_id(H5Screate_simple(1, dims, nullptr), name), H5Sclose};
  Id dcpl = untimed(H5P_DATASET_CREATE);
  Id lcpl{check_id(H5Pcreate(H5P_LINK_CREATE), name), H5Pclose};
  check(H5Pset_create_intermediate_group(lcpl.id, 1), name);
  Id ds{check_id(H5Dcreate2(g, name, type.id, space.id, lcpl.id, dcpl.id, H5P_DEFAULT), name), H5Dclose};
  std::vector<const char*> ptrs;
  for (const auto& s : v) ptrs.push_back(s.c_str());
  if (!v.empty()) check(H5Dwrite(ds.id, type.id, H5S_ALL, H5S_ALL, H5P_DEFAULT, ptrs.data()), name);
}

double read_attr_double(hid_t obj, const char* name) {
  Id a{check_id(H5Aopen(obj, name, H5P_DEFAULT), name), H5Aclose};
  double v = 0;
  check(H5Aread(a.id, H5T_NATIVE_DOUBLE, &v), name);
  return v;
}

std::string hdf5_version() {
  unsigned a, b, c;
  H5get_libversion(&a, &b, &c);
  return fmt::format("{}.{}.{}", a, b, c);
}

void fsync_path(const std::string& path, bool directory) {
  const int fd = ::open(path.c_str(), directory ? O_RDONLY | O_DIRECTORY : O_RDONLY);
  if (fd < 0) return;
  ::fsync(fd);
  ::close(fd);
}

}  // namespace

struct ShardWriter::Impl {
  std::string path, tmp;
  hid_t file = -1, shapes = -1;
  bool committed = false;
  int slot = -1;  ///< core::register_temporary of tmp (a signal removes it)
  ~Impl() { core::unregister_temporary(slot); }
  /// Closes what is open and removes the temporary file, whatever state HDF5 is in.
  void abandon();
  /// abandon(), then throws StorageError naming the file, `e` and the free space.
  [[noreturn]] void fail(const std::exception& e);
  /// Runs `fn` with HDF5's error printing off; a failure becomes fail().
  template <class Fn>
  void guarded(Fn&& fn) {
    H5E_BEGIN_TRY {
      try {
        fn();
      } catch (const std::exception& e) {
        fail(e);
      }
    }
    H5E_END_TRY;
  }
};

namespace {

/// A scalar string dataset (the config, the scene).
void write_text(hid_t f, const char* name, const std::string& text) {
  Id dcpl = untimed(H5P_DATASET_CREATE);
  Id type{check_id(H5Tcopy(H5T_C_S1), name), H5Tclose};
  check(H5Tset_size(type.id, std::max<std::size_t>(1, text.size())), name);
  Id space{check_id(H5Screate(H5S_SCALAR), name), H5Sclose};
  Id ds{check_id(H5Dcreate2(f, name, type.id, space.id, H5P_DEFAULT, dcpl.id, H5P_DEFAULT), name), H5Dclose};
  check(H5Dwrite(ds.id, type.id, H5S_ALL, H5S_ALL, H5P_DEFAULT, text.empty() ? " " : text.c_str()), name);
}

}  // namespace

ShardWriter::ShardWriter(std::string path, const ShardHeader& h) : impl_(std::make_unique<Impl>()) {
  impl_->path = std::move(path);
  impl_->tmp = impl_->path + ".tmp";
  impl_->guarded([&] { write_header(h); });
}

void ShardWriter::write_header(const ShardHeader& h) {
  impl_->slot = core::register_temporary(impl_->tmp);
  Id fcpl = untimed(H5P_FILE_CREATE);  // the root group's timestamps too
  impl_->file = check_id(H5Fcreate(impl_->tmp.c_str(), H5F_ACC_TRUNC, fcpl.id, H5P_DEFAULT),
                         "create " + impl_->tmp);
  const hid_t f = impl_->file;
  attr_string(f, "format", "hypershape-dataset");
  attr_double(f, "format_version", dataset_format_version);
  attr_string(f, "dataset_name", h.dataset_name);
  attr_string(f, "config_hash", h.config_hash);
  attr_double(f, "seed", double(h.seed));
  attr_string(f, "seed_exact", std::to_string(h.seed));  // a float64 holds only 53 bits
  attr_double(f, "dim", h.dim);
  attr_double(f, "shard_index", double(h.shard_index));
  attr_double(f, "first_shape", double(h.first_shape));
  attr_double(f, "n_shapes", double(h.n_shapes));
  attr_double(f, "n_loads", h.n_loads);
  attr_double(f, "complete", 0);
  {
    Id sw = make_group(f, "software");
    auto software = h.software;
#ifdef HYPERSHAPE_VERSION
    software["hypershape"] = HYPERSHAPE_VERSION;
#endif
    software["hdf5"] = hdf5_version();
    for (const auto& [k, v] : software) attr_string(sw.id, k, v);
  }
  write_text(f, "config", h.config_text);
  if (!h.scene_text.empty()) write_text(f, "scene", h.scene_text);
  Id shapes = make_group(f, "shapes");
  impl_->shapes = shapes.id;
  shapes.id = -1;  // owned by the writer now
}

ShardWriter::~ShardWriter() {
  if (impl_ && !impl_->committed) impl_->abandon();
}

void ShardWriter::Impl::abandon() {
  // A write that failed (a full disk) leaves HDF5 with data it still wants to flush: at close,
  // and at library shutdown, where it crashed (exit 139). Emptying the file first frees the
  // space, so the close succeeds; then the file goes.
  if (file >= 0 && ::truncate(tmp.c_str(), 0) != 0) {
    // nothing more to free
  }
  H5E_BEGIN_TRY {
    if (shapes >= 0) H5Gclose(shapes);
    if (file >= 0) H5Fclose(file);
  }
  H5E_END_TRY;
  shapes = file = -1;
  std::error_code ec;
  fs::remove(tmp, ec);
}

void ShardWriter::Impl::fail(const std::exception& e) {
  abandon();
  struct statvfs v {};
  const std::string dir = fs::path(tmp).parent_path().string();
  const double free_kb = statvfs(dir.c_str(), &v) == 0 ? double(v.f_bavail) * double(v.f_frsize) / 1024 : -1;
  throw StorageError(fmt::format("cannot write {}: {} ({:.0f} kB free on its file system after removing it{}); the shards "
                                       "written before are complete, run the same command again to resume",
                                       tmp, e.what(), free_kb, free_kb < 1024 ? ": the disk is full" : ""));
}

void ShardWriter::add(const ShardShape& s) {
  impl_->guarded([&] { add_shape(s); });
}

void ShardWriter::add_shape(const ShardShape& s) {
  Id g = make_group(impl_->shapes, fmt::format("{:06d}", s.shape.shape_id));
  attr_string(g.id, "status", s.ok ? "ok" : "failed");
  if (!s.ok) {
    attr_string(g.id, "failure", s.failure);
    attr_double(g.id, "shape_id", double(s.shape.shape_id));
    write_string_dataset(g.id, "rejected", s.shape.rejected);
    for (const auto& [k, v] : s.shape.numbers) attr_double(g.id, k, v);
    if (!s.shape.source_file.empty()) attr_string(g.id, "source_file", s.shape.source_file);
    return;
  }
  write_shape_group(g.id, s.shape);
  for (const Array& a : s.arrays) write_array(g.id, a);
  write_strings(g.id, "loads/reason", s.load_reasons);
}

void ShardWriter::commit(const std::function<void(std::uint32_t, std::uint64_t)>& before_rename) {
  impl_->guarded([&] { close_file(); });
  fsync_path(impl_->tmp, false);
  if (before_rename) before_rename(file_crc32(impl_->tmp), std::uint64_t(fs::file_size(impl_->tmp)));
  fs::rename(impl_->tmp, impl_->path);
  fsync_path(fs::path(impl_->path).parent_path().string(), true);
  impl_->committed = true;
}

void ShardWriter::close_file() {
  const hid_t f = impl_->file;
  {
    Id a{check_id(H5Aopen(f, "complete", H5P_DEFAULT), "complete"), H5Aclose};
    const double one = 1;
    check(H5Awrite(a.id, H5T_NATIVE_DOUBLE, &one), "complete");
  }
  H5Gclose(impl_->shapes);
  impl_->shapes = -1;
  check(H5Fflush(f, H5F_SCOPE_GLOBAL), "flush " + impl_->tmp);
  check(H5Fclose(f), "close " + impl_->tmp);
  impl_->file = -1;
}

namespace {

ShardHeader read_header(hid_t file, const std::string& path) {
  ShardHeader h;
  if (read_attr_string(file, "format") != "hypershape-dataset")
    throw std::runtime_error(path + ": not a hypershape dataset shard");
  if (int(read_attr_double(file, "format_version")) != dataset_format_version)
    throw std::runtime_error(path + ": unsupported format_version");
  if (read_attr_double(file, "complete") != 1) throw std::runtime_error(path + ": incomplete shard");
  h.dataset_name = read_attr_string(file, "dataset_name");
  h.config_hash = read_attr_string(file, "config_hash");
  h.seed = std::uint64_t(read_attr_double(file, "seed"));
  h.dim = int(read_attr_double(file, "dim"));
  h.shard_index = std::int64_t(read_attr_double(file, "shard_index"));
  h.first_shape = std::int64_t(read_attr_double(file, "first_shape"));
  h.n_shapes = std::int64_t(read_attr_double(file, "n_shapes"));
  h.n_loads = int(read_attr_double(file, "n_loads"));
  // (shards written before 2026-11-28 have no numerics attribute)
  if (H5Lexists(file, "software", H5P_DEFAULT) > 0) {
    Id sw{check_id(H5Gopen2(file, "software", H5P_DEFAULT), path), H5Gclose};
    if (H5Aexists(sw.id, "numerics") > 0) h.software["numerics"] = read_attr_string(sw.id, "numerics");
  }
  return h;
}

}  // namespace

ShardHeader read_shard_header(const std::string& path) {
  ShardHeader h;
  H5E_BEGIN_TRY {
    const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    if (f < 0) throw std::runtime_error(path + ": not an HDF5 file (or unreadable)");
    Id file{f, H5Fclose};
    h = read_header(file.id, path);
  }
  H5E_END_TRY;
  return h;
}

ShardSummary read_shard_summary(const std::string& path) {
  Id file{check_id(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), "open " + path), H5Fclose};
  ShardSummary out;
  out.header = read_header(file.id, path);
  auto& h = out.header;
  h.config_text = read_string(file.id, "config");
  for_each_group(file.id, "shapes", [&](const char*, hid_t g) {
    ShardSummary::Shape s;
    s.shape_id = std::int64_t(read_attr_double(g, "shape_id"));
    s.ok = read_attr_string(g, "status") == "ok";
    if (s.ok) {
      for (auto v : read_array<std::int8_t>(g, "loads/status", H5T_NATIVE_INT8)) (v == 1 ? s.loads_ok : s.loads_failed) += 1;
      if (H5Lexists(g, "stats", H5P_DEFAULT) > 0)
        for_each_link(g, "stats", [&](const char* field, hid_t st) {
          s.stats[field] = read_array<double>(st, field, H5T_NATIVE_DOUBLE);
        });
    } else {
      s.loads_failed = h.n_loads;
    }
    out.shapes.push_back(std::move(s));
  });
  return out;
}

std::uint32_t file_crc32(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read " + path);
  std::uint32_t crc = 0;
  std::vector<char> buf(1 << 20);
  while (in) {
    in.read(buf.data(), std::streamsize(buf.size()));
    const auto n = in.gcount();
    if (n > 0) crc = crc32_update(crc, buf.data(), std::size_t(n));
  }
  return crc;
}

std::string text_digest(const std::string& text) {
  std::uint64_t h = 1469598103934665603ULL;
  for (unsigned char c : text) {
    h ^= c;
    h *= 1099511628211ULL;
  }
  return fmt::format("{:016x}", h);
}

}  // namespace hypershape::io
