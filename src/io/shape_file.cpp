#include "hypershape/io/shape_file.hpp"

#include <fmt/format.h>
#include <hdf5.h>
#include <unistd.h>

#include <filesystem>

#include "h5_util.hpp"
#include "shape_group.hpp"

namespace hypershape::io {

void write_shape_group(hid_t g, const ShapeRecord& s) {
  Id bnd = group(g, "boundary");
  write_2d(bnd.id, "points", H5T_NATIVE_DOUBLE, s.boundary_points.data(), s.boundary_points.size() / s.dim, s.dim);
  write_2d(bnd.id, "facets", H5T_NATIVE_INT32, s.boundary_facets.data(), s.boundary_facets.size() / s.dim, s.dim);
  Id mesh = group(g, "mesh");
  write_2d(mesh.id, "nodes", H5T_NATIVE_DOUBLE, s.mesh_nodes.data(), s.mesh_nodes.size() / s.dim, s.dim);
  write_2d(mesh.id, "cells", H5T_NATIVE_INT64, s.mesh_cells.data(), s.mesh_cells.size() / (s.dim + 1), s.dim + 1);
  write_1d(g, "dirichlet_facets", H5T_NATIVE_INT32, s.dirichlet_facets.data(), s.dirichlet_facets.size());
  write_string_dataset(g, "rejected", s.rejected);
  attr_double(g, "shape_id", double(s.shape_id));
  for (const auto& [k, v] : s.numbers) attr_double(g, k, v);
  attr_vector(g, "dirichlet_center", s.dirichlet_center);
  if (!s.source_file.empty()) attr_string(g, "source_file", s.source_file);
}

ShapeRecord read_shape_group(hid_t g) {
  ShapeRecord s;
  hsize_t cols = 0;
  s.boundary_points = read_array<double>(g, "boundary/points", H5T_NATIVE_DOUBLE, &cols);
  s.dim = int(cols);
  s.boundary_facets = read_array<int>(g, "boundary/facets", H5T_NATIVE_INT32);
  s.mesh_nodes = read_array<double>(g, "mesh/nodes", H5T_NATIVE_DOUBLE);
  s.mesh_cells = read_array<std::int64_t>(g, "mesh/cells", H5T_NATIVE_INT64);
  s.dirichlet_facets = read_array<int>(g, "dirichlet_facets", H5T_NATIVE_INT32);
  s.rejected = read_string(g, "rejected");
  hsize_t idx = 0;
  H5Aiterate2(g, H5_INDEX_NAME, H5_ITER_INC, &idx, collect_double_attr, &s.numbers);
  s.shape_id = std::int64_t(s.numbers.at("shape_id"));
  s.numbers.erase("shape_id");
  if (H5Aexists(g, "source_file") > 0) s.source_file = read_attr_string(g, "source_file");
  return s;
}

void write_shapes(const std::string& path, const std::vector<ShapeRecord>& shapes,
                  const std::string& config_text, const std::string& name, std::uint64_t seed) {
  namespace fs = std::filesystem;
  const fs::path final_h5(path);
  const fs::path tmp = final_h5.string() + ".tmp-" + std::to_string(::getpid());
  try {
    {
      Id file{check_id(H5Fcreate(tmp.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT),
                       "create " + tmp.string()), H5Fclose};
      const int dim = shapes.empty() ? 0 : shapes.front().dim;
      attr_double(file.id, "dim", dim);
      attr_double(file.id, "seed", double(seed));
      attr_double(file.id, "n_shapes", double(shapes.size()));
      attr_string(file.id, "name", name);
#ifdef HYPERSHAPE_VERSION
      attr_string(file.id, "hypershape_version", HYPERSHAPE_VERSION);
#endif
      write_string_dataset(file.id, "config", config_text);
      Id all = group(file.id, "shapes");
      for (const ShapeRecord& s : shapes) {
        Id g = group(all.id, fmt::format("{:06d}", s.shape_id));
        write_shape_group(g.id, s);
      }
      check(H5Fflush(file.id, H5F_SCOPE_GLOBAL), "flush");
    }
    fs::rename(tmp, final_h5);
  } catch (...) {
    std::error_code ec;
    fs::remove(tmp, ec);
    throw;
  }
}

std::vector<ShapeRecord> read_shapes(const std::string& path) {
  Id file{check_id(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), "open " + path), H5Fclose};
  std::vector<ShapeRecord> out;
  for_each_group(file.id, "shapes", [&](const char*, hid_t g) { out.push_back(read_shape_group(g)); });
  return out;
}

}  // namespace hypershape::io
