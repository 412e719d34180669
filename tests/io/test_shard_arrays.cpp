// A shard's arrays, and its shape group's, are compressed here (shuffle and DEFLATE by
// libdeflate, the chunks written as stored) and read by HDF5's own filters: every value comes
// back, each dataset declares the standard filters, a chunk past the end of an array (its tail
// padding) reads as the array, and the file checksum is CRC-32 as zlib computes it.
#include <hdf5.h>

#include <catch2/catch.hpp>

#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "hypershape/io/dataset_shard.hpp"

using namespace hypershape;
namespace fs = std::filesystem;

namespace {

template <class T>
std::vector<T> read_all(hid_t file, const std::string& path, hid_t type, std::vector<hsize_t>& dims) {
  const hid_t ds = H5Dopen2(file, path.c_str(), H5P_DEFAULT);
  REQUIRE(ds >= 0);
  const hid_t space = H5Dget_space(ds);
  dims.assign(std::size_t(H5Sget_simple_extent_ndims(space)), 0);
  H5Sget_simple_extent_dims(space, dims.data(), nullptr);
  std::size_t n = 1;
  for (hsize_t d : dims) n *= std::size_t(d);
  std::vector<T> out(n);
  CHECK(H5Dread(ds, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()) >= 0);
  // The declared filters: shuffle, then deflate at level 4.
  const hid_t dcpl = H5Dget_create_plist(ds);
  REQUIRE(H5Pget_nfilters(dcpl) == 2);
  unsigned flags = 0, level = 0;
  std::size_t nvalues = 1;
  char name[64];
  CHECK(H5Pget_filter2(dcpl, 0, &flags, &nvalues, &level, sizeof name, name, nullptr) == H5Z_FILTER_SHUFFLE);
  nvalues = 1;
  CHECK(H5Pget_filter2(dcpl, 1, &flags, &nvalues, &level, sizeof name, name, nullptr) == H5Z_FILTER_DEFLATE);
  CHECK(level == 4);
  H5Pclose(dcpl);
  H5Sclose(space);
  H5Dclose(ds);
  return out;
}

}  // namespace

TEST_CASE("Shard arrays compressed by the writer read back through HDF5's filters", "[io]") {
  const fs::path dir = fs::temp_directory_path() / ("hs_shard_arrays_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string path = (dir / "s.h5").string();
  io::ShardShape s;
  s.shape.shape_id = 7;
  s.shape.dirichlet_center = {0, 0, 0};
  s.shape.mesh_nodes = {0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 1.0};  // the shape group's arrays (write_2d)
  s.shape.mesh_cells = {0, 1, 2, 1, 3, 2};
  // 600,000 doubles: chunks of 2^20 / 2 rows, so the second chunk runs past the array's end.
  std::vector<double> big(600000);
  for (std::size_t i = 0; i < big.size(); ++i) big[i] = std::sin(0.001 * double(i)) * 1e3 + double(i % 7);
  std::vector<float> grid(3 * 5 * 4 * 3);  // loads/: one load case per chunk
  for (std::size_t i = 0; i < grid.size(); ++i) grid[i] = float(i) * 0.25f - 3.0f;
  std::vector<std::int64_t> cells{0, 1, 2, -5, 1LL << 40, 3};
  std::vector<std::int8_t> inside{1, 0, 1, 1, -1};
  s.arrays.push_back({"big", {big.size()}, big, "", ""});
  s.arrays.push_back({"loads/grid", {3, 5, 4, 3}, grid, "", ""});
  s.arrays.push_back({"cells", {3, 2}, cells, "", ""});
  s.arrays.push_back({"grid/inside", {5}, inside, "", ""});
  s.load_reasons = {"a", "b", "c"};
  {
    io::ShardHeader h;
    h.dataset_name = "t";
    io::ShardWriter w(path, h);
    w.add(s);
    w.commit();
  }
  const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  REQUIRE(f >= 0);
  std::vector<hsize_t> dims;
  // In double parentheses: a mismatch prints false, not 600,000 values.
  CHECK((read_all<double>(f, "shapes/000007/big", H5T_NATIVE_DOUBLE, dims) == big));
  CHECK(dims == std::vector<hsize_t>{600000});
  CHECK((read_all<float>(f, "shapes/000007/loads/grid", H5T_NATIVE_FLOAT, dims) == grid));
  CHECK(dims == std::vector<hsize_t>{3, 5, 4, 3});
  CHECK((read_all<std::int64_t>(f, "shapes/000007/cells", H5T_NATIVE_INT64, dims) == cells));
  CHECK((read_all<std::int8_t>(f, "shapes/000007/grid/inside", H5T_NATIVE_INT8, dims) == inside));
  CHECK((read_all<double>(f, "shapes/000007/mesh/nodes", H5T_NATIVE_DOUBLE, dims) == s.shape.mesh_nodes));
  CHECK(dims == std::vector<hsize_t>{4, 2});
  CHECK((read_all<std::int64_t>(f, "shapes/000007/mesh/cells", H5T_NATIVE_INT64, dims) == s.shape.mesh_cells));
  H5Fclose(f);
  // The check value of CRC-32 (zlib's, and Python's zlib.crc32 that hypershape_data.py checks).
  const std::string digits = (dir / "digits").string();
  std::ofstream(digits) << "123456789";
  CHECK(io::file_crc32(digits) == 0xCBF43926u);
  fs::remove_all(dir);
}
