#include "hypershape/io/solution_file.hpp"

#include <hdf5.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "h5_util.hpp"

namespace hypershape::io {

namespace {

const char* xdmf_topology(int dim, int degree) {
  if (dim == 2) return degree == 1 ? "Triangle" : "Triangle_6";
  return degree == 1 ? "Tetrahedron" : "Tetrahedron_10";
}

void write_xdmf(const std::string& path, const std::string& h5_name, const SolutionRecord& r) {
  const std::size_t n_nodes = r.nodes.size() / r.dim;
  const std::size_t k = r.dim == 2 ? (r.degree == 1 ? 3 : 6) : (r.degree == 1 ? 4 : 10);
  const std::size_t n_cells = r.cells.size() / k;
  std::ofstream x(path);
  x << "<?xml version=\"1.0\" ?>\n<Xdmf Version=\"3.0\">\n <Domain>\n  <Grid Name=\"solution\" GridType=\"Uniform\">\n"
    << "   <Topology TopologyType=\"" << xdmf_topology(r.dim, r.degree) << "\" NumberOfElements=\"" << n_cells << "\">\n"
    << "    <DataItem Dimensions=\"" << n_cells << " " << k << "\" NumberType=\"Int\" Precision=\"8\" Format=\"HDF\">"
    << h5_name << ":/mesh/cells</DataItem>\n   </Topology>\n"
    << "   <Geometry GeometryType=\"" << (r.dim == 2 ? "XY" : "XYZ") << "\">\n"
    << "    <DataItem Dimensions=\"" << n_nodes << " " << r.dim << "\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">"
    << h5_name << ":/mesh/nodes</DataItem>\n   </Geometry>\n"
    << "   <Attribute Name=\"displacement\" AttributeType=\"Vector\" Center=\"Node\">\n"
    << "    <DataItem Dimensions=\"" << n_nodes << " 3\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">"
    << h5_name << ":/xdmf/displacement3</DataItem>\n   </Attribute>\n"
    << "  </Grid>\n </Domain>\n</Xdmf>\n";
  if (!x) throw std::runtime_error("cannot write " + path);
}

}  // namespace

void write_solution(const std::string& path, const SolutionRecord& r) {
  namespace fs = std::filesystem;
  const fs::path final_h5(path);
  fs::path final_xdmf(path);
  final_xdmf.replace_extension(".xdmf");
  const std::string tag = ".tmp-" + std::to_string(::getpid());
  const fs::path tmp_h5 = final_h5.string() + tag, tmp_xdmf = final_xdmf.string() + tag;
  try {
    {
      Id file{check_id(H5Fcreate(tmp_h5.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT),
                       "create " + tmp_h5.string()), H5Fclose};
      Id mesh{check_id(H5Gcreate2(file.id, "mesh", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), "mesh"), H5Gclose};
      Id fields{check_id(H5Gcreate2(file.id, "fields", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), "fields"), H5Gclose};
      Id inputs{check_id(H5Gcreate2(file.id, "inputs", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), "inputs"), H5Gclose};
      Id xdmf{check_id(H5Gcreate2(file.id, "xdmf", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), "xdmf"), H5Gclose};
      const hsize_t n_nodes = r.nodes.size() / r.dim;
      const hsize_t k = r.dim == 2 ? (r.degree == 1 ? 3 : 6) : (r.degree == 1 ? 4 : 10);
      write_2d(mesh.id, "nodes", H5T_NATIVE_DOUBLE, r.nodes.data(), n_nodes, r.dim);
      write_2d(mesh.id, "cells", H5T_NATIVE_INT64, r.cells.data(), r.cells.size() / k, k);
      write_2d(fields.id, "displacement", H5T_NATIVE_DOUBLE, r.displacement.data(), n_nodes, r.dim);
      std::vector<double> u3(n_nodes * 3, 0.0);
      for (hsize_t i = 0; i < n_nodes; ++i)
        for (int c = 0; c < r.dim; ++c) u3[i * 3 + c] = r.displacement[i * r.dim + c];
      write_2d(xdmf.id, "displacement3", H5T_NATIVE_DOUBLE, u3.data(), n_nodes, 3);
      write_string_dataset(inputs.id, "scene", r.scene_text);
      if (!r.timings.empty()) {
        Id timings{check_id(H5Gcreate2(file.id, "timings", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), "timings"),
                   H5Gclose};
        for (const auto& [name, v] : r.timings)
          write_1d(timings.id, name.c_str(), H5T_NATIVE_DOUBLE, v.data(), v.size());
      }
      attr_double(file.id, "dim", r.dim);
      attr_double(file.id, "degree", r.degree);
      attr_double(file.id, "n_vertices", double(r.n_vertices));
      attr_string(mesh.id, "units", "reference coordinates, same length unit as the scene");
      attr_string(fields.id, "units", "displacement, same length unit as the mesh");
      for (auto& [k2, v] : r.numbers) attr_double(file.id, k2, v);
      for (auto& [k2, v] : r.strings) attr_string(file.id, k2, v);
      check(H5Fflush(file.id, H5F_SCOPE_GLOBAL), "flush");
    }
    write_xdmf(tmp_xdmf.string(), final_h5.filename().string(), r);
    fs::rename(tmp_h5, final_h5);
    fs::rename(tmp_xdmf, final_xdmf);
  } catch (...) {
    std::error_code ec;
    fs::remove(tmp_h5, ec);
    fs::remove(tmp_xdmf, ec);
    throw;
  }
}

SolutionRecord read_solution(const std::string& path) {
  SolutionRecord r;
  Id file{check_id(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), "open " + path), H5Fclose};
  auto read_2d = [&](const char* name, hid_t type, auto& out, hsize_t& rows, hsize_t& cols) {
    Id ds{check_id(H5Dopen2(file.id, name, H5P_DEFAULT), name), H5Dclose};
    Id sp{check_id(H5Dget_space(ds.id), name), H5Sclose};
    hsize_t dims[2] = {0, 0};
    H5Sget_simple_extent_dims(sp.id, dims, nullptr);
    rows = dims[0];
    cols = dims[1];
    out.resize(rows * cols);
    if (rows) check(H5Dread(ds.id, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()), name);
  };
  hsize_t rows, cols;
  read_2d("/mesh/nodes", H5T_NATIVE_DOUBLE, r.nodes, rows, cols);
  r.dim = int(cols);
  read_2d("/mesh/cells", H5T_NATIVE_INT64, r.cells, rows, cols);
  r.degree = (cols == 6 || cols == 10) ? 2 : 1;
  read_2d("/fields/displacement", H5T_NATIVE_DOUBLE, r.displacement, rows, cols);
  return r;
}

}  // namespace hypershape::io
