#include "hypershape/io/shape_file.hpp"

#include <fmt/format.h>
#include <hdf5.h>
#include <unistd.h>

#include <filesystem>

#include "h5_util.hpp"

namespace hypershape::io {

namespace {

void write_1d(hid_t parent, const char* name, hid_t type, const void* data, hsize_t n) {
  hsize_t dims[1] = {n};
  Id space{check_id(H5Screate_simple(1, dims, nullptr), name), H5Sclose};
  Id ds{check_id(H5Dcreate2(parent, name, type, space.id, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), name), H5Dclose};
  if (n > 0) check(H5Dwrite(ds.id, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data), name);
}

void attr_vector(hid_t obj, const char* name, const std::vector<double>& v) {
  hsize_t dims[1] = {v.size()};
  Id space{check_id(H5Screate_simple(1, dims, nullptr), name), H5Sclose};
  Id a{check_id(H5Acreate2(obj, name, H5T_NATIVE_DOUBLE, space.id, H5P_DEFAULT, H5P_DEFAULT), name), H5Aclose};
  check(H5Awrite(a.id, H5T_NATIVE_DOUBLE, v.data()), name);
}

Id group(hid_t parent, const std::string& name) {
  return {check_id(H5Gcreate2(parent, name.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), name), H5Gclose};
}

template <class T>
std::vector<T> read_array(hid_t parent, const char* name, hid_t type, hsize_t* cols = nullptr) {
  Id ds{check_id(H5Dopen2(parent, name, H5P_DEFAULT), name), H5Dclose};
  Id sp{check_id(H5Dget_space(ds.id), name), H5Sclose};
  const int rank = H5Sget_simple_extent_ndims(sp.id);
  hsize_t dims[2] = {0, 1};
  H5Sget_simple_extent_dims(sp.id, dims, nullptr);
  if (cols) *cols = rank == 2 ? dims[1] : 1;
  std::vector<T> out(dims[0] * (rank == 2 ? dims[1] : 1));
  if (!out.empty()) check(H5Dread(ds.id, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()), name);
  return out;
}

std::string read_string(hid_t parent, const char* name) {
  Id ds{check_id(H5Dopen2(parent, name, H5P_DEFAULT), name), H5Dclose};
  Id type{check_id(H5Dget_type(ds.id), name), H5Tclose};
  std::string s(H5Tget_size(type.id), '\0');
  check(H5Dread(ds.id, type.id, H5S_ALL, H5S_ALL, H5P_DEFAULT, s.data()), name);
  while (!s.empty() && s.back() == '\0') s.pop_back();
  return s == " " ? std::string() : s;
}

herr_t collect_double_attr(hid_t obj, const char* name, const H5A_info_t*, void* data) {
  auto& numbers = *static_cast<std::map<std::string, double>*>(data);
  Id a{H5Aopen(obj, name, H5P_DEFAULT), H5Aclose};
  if (a.id < 0) return -1;
  Id sp{H5Aget_space(a.id), H5Sclose};
  Id type{H5Aget_type(a.id), H5Tclose};
  if (H5Tget_class(type.id) == H5T_FLOAT && H5Sget_simple_extent_npoints(sp.id) == 1) {
    double v = 0.0;
    if (H5Aread(a.id, H5T_NATIVE_DOUBLE, &v) < 0) return -1;
    numbers[name] = v;
  }
  return 0;
}

}  // namespace

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
        Id bnd = group(g.id, "boundary");
        write_2d(bnd.id, "points", H5T_NATIVE_DOUBLE, s.boundary_points.data(), s.boundary_points.size() / s.dim, s.dim);
        write_2d(bnd.id, "facets", H5T_NATIVE_INT32, s.boundary_facets.data(), s.boundary_facets.size() / s.dim, s.dim);
        Id mesh = group(g.id, "mesh");
        write_2d(mesh.id, "nodes", H5T_NATIVE_DOUBLE, s.mesh_nodes.data(), s.mesh_nodes.size() / s.dim, s.dim);
        write_2d(mesh.id, "cells", H5T_NATIVE_INT64, s.mesh_cells.data(), s.mesh_cells.size() / (s.dim + 1), s.dim + 1);
        write_1d(g.id, "dirichlet_facets", H5T_NATIVE_INT32, s.dirichlet_facets.data(), s.dirichlet_facets.size());
        write_string_dataset(g.id, "rejected", s.rejected);
        attr_double(g.id, "shape_id", double(s.shape_id));
        for (const auto& [k, v] : s.numbers) attr_double(g.id, k, v);
        attr_vector(g.id, "dirichlet_center", s.dirichlet_center);
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
  Id all{check_id(H5Gopen2(file.id, "shapes", H5P_DEFAULT), "shapes"), H5Gclose};
  H5G_info_t info;
  check(H5Gget_info(all.id, &info), "shapes");
  std::vector<ShapeRecord> out;
  for (hsize_t i = 0; i < info.nlinks; ++i) {
    char name[64];
    H5Lget_name_by_idx(all.id, ".", H5_INDEX_NAME, H5_ITER_INC, i, name, sizeof name, H5P_DEFAULT);
    Id g{check_id(H5Gopen2(all.id, name, H5P_DEFAULT), name), H5Gclose};
    ShapeRecord s;
    hsize_t cols = 0;
    s.boundary_points = read_array<double>(g.id, "boundary/points", H5T_NATIVE_DOUBLE, &cols);
    s.dim = int(cols);
    s.boundary_facets = read_array<int>(g.id, "boundary/facets", H5T_NATIVE_INT32);
    s.mesh_nodes = read_array<double>(g.id, "mesh/nodes", H5T_NATIVE_DOUBLE);
    s.mesh_cells = read_array<std::int64_t>(g.id, "mesh/cells", H5T_NATIVE_INT64);
    s.dirichlet_facets = read_array<int>(g.id, "dirichlet_facets", H5T_NATIVE_INT32);
    s.rejected = read_string(g.id, "rejected");
    hsize_t idx = 0;
    H5Aiterate2(g.id, H5_INDEX_NAME, H5_ITER_INC, &idx, collect_double_attr, &s.numbers);
    s.shape_id = std::int64_t(s.numbers.at("shape_id"));
    s.numbers.erase("shape_id");
    out.push_back(std::move(s));
  }
  return out;
}

}  // namespace hypershape::io
