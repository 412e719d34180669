#pragma once
/// Small HDF5 helpers shared by the writers in src/io/ (internal; only io/ includes hdf5.h).
#include <hdf5.h>

#include <algorithm>
#include <map>
#include <vector>
#include <stdexcept>
#include <string>

#include "chunk_deflate.hpp"

namespace hypershape::io {

inline void check(herr_t status, const std::string& what) {
  if (status < 0) throw std::runtime_error("HDF5 failed: " + what);
}
inline hid_t check_id(hid_t id, const std::string& what) {
  if (id < 0) throw std::runtime_error("HDF5 failed: " + what);
  return id;
}

/// Closes an HDF5 id on scope exit.
struct Id {
  hid_t id;
  herr_t (*close)(hid_t);
  ~Id() {
    if (id >= 0) close(id);
  }
};

/// A creation property list (dataset, group or file) without object timestamps: the same data
/// gives the same bytes, run after run.
inline Id untimed(hid_t cls) {
  Id p{check_id(H5Pcreate(cls), "plist"), H5Pclose};
  check(H5Pset_obj_track_times(p.id, false), "track times");
  return p;
}

/// A rows x cols array, chunked by 16384 rows, shuffled and deflated as the shards' arrays are
/// (chunk_deflate.hpp).
inline void write_2d(hid_t parent, const char* name, hid_t type, const void* data, hsize_t rows, hsize_t cols) {
  const std::vector<hsize_t> dims{rows, cols}, chunk{std::min<hsize_t>(rows, 16384), cols};
  Id space{check_id(H5Screate_simple(2, dims.data(), nullptr), name), H5Sclose};
  Id plist = untimed(H5P_DATASET_CREATE);
  if (rows > 0) {
    declare_deflated_chunks(plist.id, chunk, name);
  }
  Id ds{check_id(H5Dcreate2(parent, name, type, space.id, H5P_DEFAULT, plist.id, H5P_DEFAULT), name), H5Dclose};
  if (rows > 0) write_deflated_chunks(ds.id, data, dims, chunk, H5Tget_size(type));
}

inline void attr_double(hid_t obj, const std::string& name, double v) {
  Id space{check_id(H5Screate(H5S_SCALAR), name), H5Sclose};
  Id a{check_id(H5Acreate2(obj, name.c_str(), H5T_NATIVE_DOUBLE, space.id, H5P_DEFAULT, H5P_DEFAULT), name), H5Aclose};
  check(H5Awrite(a.id, H5T_NATIVE_DOUBLE, &v), name);
}

inline void attr_string(hid_t obj, const std::string& name, const std::string& v) {
  Id type{check_id(H5Tcopy(H5T_C_S1), name), H5Tclose};
  check(H5Tset_size(type.id, std::max<std::size_t>(1, v.size())), name);
  Id space{check_id(H5Screate(H5S_SCALAR), name), H5Sclose};
  Id a{check_id(H5Acreate2(obj, name.c_str(), type.id, space.id, H5P_DEFAULT, H5P_DEFAULT), name), H5Aclose};
  check(H5Awrite(a.id, type.id, v.empty() ? " " : v.c_str()), name);
}

inline void write_string_dataset(hid_t parent, const char* name, const std::string& v) {
  Id type{check_id(H5Tcopy(H5T_C_S1), name), H5Tclose};
  check(H5Tset_size(type.id, std::max<std::size_t>(1, v.size())), name);
  Id space{check_id(H5Screate(H5S_SCALAR), name), H5Sclose};
  Id dcpl = untimed(H5P_DATASET_CREATE);
  Id ds{check_id(H5Dcreate2(parent, name, type.id, space.id, H5P_DEFAULT, dcpl.id, H5P_DEFAULT), name), H5Dclose};
  check(H5Dwrite(ds.id, type.id, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.empty() ? " " : v.c_str()), name);
}


inline void write_1d(hid_t parent, const char* name, hid_t type, const void* data, hsize_t n) {
  hsize_t dims[1] = {n};
  Id space{check_id(H5Screate_simple(1, dims, nullptr), name), H5Sclose};
  Id dcpl = untimed(H5P_DATASET_CREATE);
  Id ds{check_id(H5Dcreate2(parent, name, type, space.id, H5P_DEFAULT, dcpl.id, H5P_DEFAULT), name), H5Dclose};
  if (n > 0) check(H5Dwrite(ds.id, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data), name);
}

inline void attr_vector(hid_t obj, const char* name, const std::vector<double>& v) {
  hsize_t dims[1] = {v.size()};
  Id space{check_id(H5Screate_simple(1, dims, nullptr), name), H5Sclose};
  Id a{check_id(H5Acreate2(obj, name, H5T_NATIVE_DOUBLE, space.id, H5P_DEFAULT, H5P_DEFAULT), name), H5Aclose};
  check(H5Awrite(a.id, H5T_NATIVE_DOUBLE, v.data()), name);
}

/// Calls fn(name, id of the group `parent`/`path`) for every link in that group, in name order.
template <class Fn>
void for_each_link(hid_t parent, const char* path, Fn&& fn) {
  Id all{check_id(H5Gopen2(parent, path, H5P_DEFAULT), path), H5Gclose};
  H5G_info_t info;
  check(H5Gget_info(all.id, &info), path);
  for (hsize_t i = 0; i < info.nlinks; ++i) {
    char name[128];
    H5Lget_name_by_idx(all.id, ".", H5_INDEX_NAME, H5_ITER_INC, i, name, sizeof name, H5P_DEFAULT);
    fn(static_cast<const char*>(name), all.id);
  }
}

/// Calls fn(name, group id) for every group under `parent`/`path`, in name order.
template <class Fn>
void for_each_group(hid_t parent, const char* path, Fn&& fn) {
  for_each_link(parent, path, [&](const char* name, hid_t all) {
    Id g{check_id(H5Gopen2(all, name, H5P_DEFAULT), name), H5Gclose};
    fn(name, g.id);
  });
}

inline Id group(hid_t parent, const std::string& name) {
  Id gcpl = untimed(H5P_GROUP_CREATE);
  return {check_id(H5Gcreate2(parent, name.c_str(), H5P_DEFAULT, gcpl.id, H5P_DEFAULT), name), H5Gclose};
}

template <class T>
inline std::vector<T> read_array(hid_t parent, const char* name, hid_t type, hsize_t* cols = nullptr) {
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

inline std::string read_string(hid_t parent, const char* name) {
  Id ds{check_id(H5Dopen2(parent, name, H5P_DEFAULT), name), H5Dclose};
  Id type{check_id(H5Dget_type(ds.id), name), H5Tclose};
  std::string s(H5Tget_size(type.id), '\0');
  check(H5Dread(ds.id, type.id, H5S_ALL, H5S_ALL, H5P_DEFAULT, s.data()), name);
  while (!s.empty() && s.back() == '\0') s.pop_back();
  return s == " " ? std::string() : s;
}

inline std::string read_attr_string(hid_t obj, const char* name) {
  Id a{check_id(H5Aopen(obj, name, H5P_DEFAULT), name), H5Aclose};
  Id type{check_id(H5Aget_type(a.id), name), H5Tclose};
  std::string s(H5Tget_size(type.id), '\0');
  check(H5Aread(a.id, type.id, s.data()), name);
  while (!s.empty() && s.back() == '\0') s.pop_back();
  return s == " " ? std::string() : s;
}

inline herr_t collect_double_attr(hid_t obj, const char* name, const H5A_info_t*, void* data) {
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

}  // namespace hypershape::io
