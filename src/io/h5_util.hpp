#pragma once
/// Small HDF5 helpers shared by the writers in src/io/ (internal; only io/ includes hdf5.h).
#include <hdf5.h>

#include <algorithm>
#include <stdexcept>
#include <string>

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

inline void write_2d(hid_t parent, const char* name, hid_t type, const void* data, hsize_t rows, hsize_t cols) {
  hsize_t dims[2] = {rows, cols};
  Id space{check_id(H5Screate_simple(2, dims, nullptr), name), H5Sclose};
  Id plist{check_id(H5Pcreate(H5P_DATASET_CREATE), name), H5Pclose};
  if (rows > 0) {
    hsize_t chunk[2] = {std::min<hsize_t>(rows, 16384), cols};
    check(H5Pset_chunk(plist.id, 2, chunk), name);
    check(H5Pset_deflate(plist.id, 4), name);
  }
  Id ds{check_id(H5Dcreate2(parent, name, type, space.id, H5P_DEFAULT, plist.id, H5P_DEFAULT), name), H5Dclose};
  if (rows > 0) check(H5Dwrite(ds.id, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data), name);
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
  Id ds{check_id(H5Dcreate2(parent, name, type.id, space.id, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), name), H5Dclose};
  check(H5Dwrite(ds.id, type.id, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.empty() ? " " : v.c_str()), name);
}

}  // namespace hypershape::io
