#include "hypershape/factory/shape_set.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstring>

#include "hypershape/core/collective.hpp"
#include "hypershape/core/input_error.hpp"
#include "hypershape/core/log.hpp"
#include "hypershape/core/petsc_handle.hpp"
#include "hypershape/factory/dataset_scene.hpp"

namespace hypershape::factory {

namespace {

/// Byte packing of records for MPI_Gatherv.
class Packer {
 public:
  template <class T>
  void put(const std::vector<T>& v) {
    put_scalar(std::uint64_t(v.size()));
    append(v.data(), v.size() * sizeof(T));
  }
  template <class T>
  void put_scalar(T x) {
    append(&x, sizeof x);
  }
  void put(const std::string& s) {
    put_scalar(std::uint64_t(s.size()));
    append(s.data(), s.size());
  }
  std::vector<char> bytes;

 private:
  void append(const void* p, std::size_t n) {
    const char* c = static_cast<const char*>(p);
    bytes.insert(bytes.end(), c, c + n);
  }
};

class Unpacker {
 public:
  Unpacker(const char* p, const char* end) : p_(p), end_(end) {}
  template <class T>
  void get(std::vector<T>& v) {
    v.resize(get_scalar<std::uint64_t>());
    take(v.data(), v.size() * sizeof(T));
  }
  void get(std::string& s) {
    s.resize(get_scalar<std::uint64_t>());
    take(s.data(), s.size());
  }
  template <class T>
  T get_scalar() {
    T x;
    take(&x, sizeof x);
    return x;
  }
  bool done() const { return p_ >= end_; }

 private:
  void take(void* dst, std::size_t n) {
    if (p_ + n > end_) throw std::logic_error("shape record unpacking overran its buffer");
    std::memcpy(dst, p_, n);
    p_ += n;
  }
  const char* p_;
  const char* end_;
};

void pack(const io::ShapeRecord& r, Packer& p) {
  p.put_scalar(r.shape_id);
  p.put_scalar(std::int32_t(r.dim));
  p.put(r.boundary_points);
  p.put(r.boundary_facets);
  p.put(r.mesh_nodes);
  p.put(r.mesh_cells);
  p.put(r.dirichlet_facets);
  p.put(r.dirichlet_center);
  std::vector<double> values;
  std::string keys;
  for (const auto& [k, v] : r.numbers) keys += k + '\n', values.push_back(v);
  p.put(keys);
  p.put(values);
  p.put(r.rejected);
  p.put(r.source_file);
}

io::ShapeRecord unpack(Unpacker& u) {
  io::ShapeRecord r;
  r.shape_id = u.get_scalar<std::int64_t>();
  r.dim = u.get_scalar<std::int32_t>();
  u.get(r.boundary_points);
  u.get(r.boundary_facets);
  u.get(r.mesh_nodes);
  u.get(r.mesh_cells);
  u.get(r.dirichlet_facets);
  u.get(r.dirichlet_center);
  std::string keys;
  std::vector<double> values;
  u.get(keys);
  u.get(values);
  std::size_t start = 0;
  for (double v : values) {
    const std::size_t end = keys.find('\n', start);
    r.numbers[keys.substr(start, end - start)] = v;
    start = end + 1;
  }
  u.get(r.rejected);
  u.get(r.source_file);
  return r;
}

}  // namespace

io::ShapeRecord to_record(const ShapeSample& s) {
  io::ShapeRecord r;
  r.shape_id = s.shape_id;
  r.dim = s.boundary.dim;
  r.boundary_points = s.boundary.points;
  r.boundary_facets = s.boundary.facets;
  r.mesh_nodes = s.mesh.coords;
  r.mesh_cells.assign(s.mesh.cells.begin(), s.mesh.cells.end());
  r.dirichlet_facets = s.dirichlet_facets;
  r.dirichlet_center.assign(s.dirichlet_center.begin(), s.dirichlet_center.begin() + 3);
  r.source_file = s.source_file;
  const auto& m = s.metrics;
  r.numbers = {{"attempt", s.attempt},
               {"failed", 0},
               {"measure", m.measure},
               {"boundary_measure", m.boundary_measure},
               {"isoperimetric_ratio", m.isoperimetric_ratio},
               {"hausdorff_to_base", m.hausdorff_to_base},
               {"min_local_feature_size", m.min_local_feature_size},
               {"min_exterior_gap", m.min_exterior_gap},
               {"n_boundary_facets", double(m.n_boundary_facets)},
               {"n_vertices", double(s.mesh.n_vertices())},
               {"n_cells", double(s.mesh.n_cells())},
               {"mesh_min_angle_deg", s.quality.min_angle_deg},
               {"mesh_min_shape", s.quality.min_shape},
               {"dirichlet_radius", s.dirichlet_radius},
               {"seconds_draw", s.seconds_draw},
               {"seconds_mesh", s.seconds_mesh},
               {"seconds_metrics", s.seconds_metrics},
               {"n_rejected", double(s.rejected.size())}};
  for (const auto& rej : s.rejected)
    r.rejected += fmt::format("{} {}: {}\n", rej.attempt, rej.stage, rej.reason);
  return r;
}

std::optional<geometry::Boundary> load_dataset_base(const config::DatasetConfig& config) {
  try {
    return load_base(config.shapes);
  } catch (const core::InputError& e) {
    throw core::InputError(config.source,
                           config.shapes.base == "directory" ? "shapes.base_dir" : "shapes.base_file",
                           e.what());
  }
}

std::vector<io::ShapeRecord> make_shape_range(MPI_Comm comm, const config::DatasetConfig& config,
                                              std::int64_t first, std::int64_t count) {
  const int rank = core::rank(comm), size = core::size(comm);
  const std::optional<geometry::Boundary> base = load_dataset_base(config);
  Packer mine;
  std::int64_t n_mine = 0;
  for (std::int64_t id = first + rank; id < first + count; id += size) {
    io::ShapeRecord r;
    try {
      const ShapeSample s = make_shape(shape_config(config, id), base, config.seed, id);
      r = to_record(s);
      core::log_line(MPI_COMM_SELF, core::Verbosity::normal,
                     fmt::format("[rank {}] shape {}: {} boundary facets, {} vertices, {} cells, "
                                 "attempt {}, {:.2f} s", rank, id, s.boundary.n_facets(),
                                 s.mesh.n_vertices(), s.mesh.n_cells(), s.attempt,
                                 s.seconds_draw + s.seconds_mesh + s.seconds_metrics));
    } catch (const std::runtime_error& e) {
      r.shape_id = id;
      r.dim = config.shapes.dim;
      r.dirichlet_center = {0, 0, 0};
      r.numbers = {{"failed", 1}};
      r.rejected = e.what();
      r.source_file = source_file(config.shapes, id);
      core::log_line(MPI_COMM_SELF, core::Verbosity::normal,
                     fmt::format("[rank {}] shape {} FAILED: {}", rank, id, e.what()));
    }
    pack(r, mine);
    ++n_mine;
  }
  // Gather the byte streams on rank 0.
  int my_bytes = int(mine.bytes.size());
  std::vector<int> counts(size), displs(size);
  MPI_Gather(&my_bytes, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, comm);
  std::vector<char> all;
  if (rank == 0) {
    for (int r = 0, off = 0; r < size; ++r) displs[r] = off, off += counts[r];
    all.resize(std::size_t(displs.back() + counts.back()));
  }
  MPI_Gatherv(mine.bytes.data(), my_bytes, MPI_CHAR, all.data(), counts.data(), displs.data(),
              MPI_CHAR, 0, comm);
  std::vector<io::ShapeRecord> out;
  if (rank != 0) return out;
  for (int r = 0; r < size; ++r) {
    Unpacker u(all.data() + displs[r], all.data() + displs[r] + counts[r]);
    while (!u.done()) out.push_back(unpack(u));
  }
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.shape_id < b.shape_id; });
  return out;
}

}  // namespace hypershape::factory
