#include "hypershape/io/dataset_xdmf.hpp"

#include <fmt/format.h>
#include <hdf5.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string_view>

#include "h5_util.hpp"

namespace hypershape::io {

namespace {

namespace fs = std::filesystem;
using Dims = std::vector<hsize_t>;

/// Per-load-case fields (L x n x c in the shard) that get one (n x c) view per load case.
constexpr const char* kLoadFields[] = {"displacement", "traction"};

Dims dims_of(hid_t g, const char* name) {
  // H5Lexists needs every intermediate group to exist: check the path step by step.
  std::string path;
  for (std::string_view rest = name; !rest.empty();) {
    const auto slash = rest.find('/');
    path += (path.empty() ? "" : "/") + std::string(rest.substr(0, slash));
    if (H5Lexists(g, path.c_str(), H5P_DEFAULT) <= 0) return {};
    rest = slash == std::string_view::npos ? std::string_view() : rest.substr(slash + 1);
  }
  Id ds{check_id(H5Dopen2(g, name, H5P_DEFAULT), name), H5Dclose};
  Id sp{check_id(H5Dget_space(ds.id), name), H5Sclose};
  Dims d(std::size_t(H5Sget_simple_extent_ndims(sp.id)));
  H5Sget_simple_extent_dims(sp.id, d.data(), nullptr);
  return d;
}

/// What the views of one solved shape need from its group in the shard.
struct ShapeInfo {
  std::string name;  // "000003"
  Dims nodes, cells, sdf, dirichlet_distance;
  std::map<std::string, Dims> load_fields;  // field -> L x n x c (only those present)
  hsize_t n_loads = 0;
};

std::vector<ShapeInfo> read_shapes(hid_t file) {
  std::vector<ShapeInfo> shapes;
  for_each_group(file, "shapes", [&](const char* name, hid_t g) {
    ShapeInfo s{name, dims_of(g, "nodes"), dims_of(g, "cells"), dims_of(g, "point_cloud/sdf"),
                dims_of(g, "point_cloud/dirichlet_distance"), {}, 0};
    if (s.nodes.size() != 2 || s.cells.size() != 2) return;  // a failed shape: nothing to show
    for (const char* f : kLoadFields) {
      const auto d = dims_of(g, (std::string("loads/") + f).c_str());
      if (d.size() == 3) s.load_fields[f] = d, s.n_loads = d[0];
    }
    shapes.push_back(std::move(s));
  });
  return shapes;
}

/// A virtual dataset `name` (n x c) in `parent` that maps row `l` of the shard's (L x n x c)
/// dataset `source`: no data are copied; a missing shard reads as NaN.
void write_row_view(hid_t parent, const std::string& name, const std::string& shard, const std::string& source,
                    const Dims& d, hsize_t l) {
  const hsize_t view_dims[2] = {d[1], d[2]}, start[3] = {l, 0, 0}, count[3] = {1, d[1], d[2]};
  Id view{check_id(H5Screate_simple(2, view_dims, nullptr), name), H5Sclose};
  Id src{check_id(H5Screate_simple(3, d.data(), nullptr), name), H5Sclose};
  check(H5Sselect_hyperslab(src.id, H5S_SELECT_SET, start, nullptr, count, nullptr), name);
  Id dcpl{check_id(H5Pcreate(H5P_DATASET_CREATE), name), H5Pclose};
  const double fill = std::numeric_limits<double>::quiet_NaN();
  check(H5Pset_fill_value(dcpl.id, H5T_NATIVE_DOUBLE, &fill), name);
  check(H5Pset_virtual(dcpl.id, view.id, shard.c_str(), source.c_str(), src.id), name);
  Id lcpl{check_id(H5Pcreate(H5P_LINK_CREATE), name), H5Pclose};
  check(H5Pset_create_intermediate_group(lcpl.id, 1), name);
  Id ds{check_id(H5Dcreate2(parent, name.c_str(), H5T_IEEE_F64LE, view.id, lcpl.id, dcpl.id, H5P_DEFAULT), name),
        H5Dclose};
}

/// The companion file: /shapes/<id>/<field>/<l> for every load field and load case.
void write_views_file(const std::vector<ShapeInfo>& shapes, const std::string& shard_rel, const std::string& path) {
  const std::string tmp = path + fmt::format(".tmp-{}", ::getpid());
  {
    Id file{check_id(H5Fcreate(tmp.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), "create " + tmp), H5Fclose};
    attr_string(file.id, "source", shard_rel);
    for (const auto& s : shapes)
      for (const auto& [field, d] : s.load_fields)
        for (hsize_t l = 0; l < d[0]; ++l)
          write_row_view(file.id, fmt::format("shapes/{}/{}/{}", s.name, field, l), shard_rel,
                         fmt::format("/shapes/{}/loads/{}", s.name, field), d, l);
  }
  fs::rename(tmp, path);
}

std::string join(const Dims& d) {
  std::string s;
  for (auto v : d) s += (s.empty() ? "" : " ") + std::to_string(v);
  return s;
}

std::string hdf_item(const std::string& ref, const Dims& d, const char* type, int precision) {
  return fmt::format("<DataItem Dimensions=\"{}\" NumberType=\"{}\" Precision=\"{}\" Format=\"HDF\">{}</DataItem>",
                     join(d), type, precision, ref);
}

std::string attribute(const std::string& name, const char* type, const std::string& item) {
  return fmt::format("<Attribute Name=\"{}\" AttributeType=\"{}\" Center=\"Node\">{}</Attribute>", name, type, item);
}

/// Mesh and per-shape fields of one shape, repeated in each of its time steps.
std::string shape_static_xml(const ShapeInfo& s, const std::string& shard_rel) {
  const hsize_t dim = s.nodes[1], per = s.cells[1];
  const char* topo = dim == 2 ? (per == 3 ? "Triangle" : "Triangle_6") : (per == 4 ? "Tetrahedron" : "Tetrahedron_10");
  const std::string base = shard_rel + ":/shapes/" + s.name + "/";
  std::string x = fmt::format(
      "<Topology TopologyType=\"{}\" NumberOfElements=\"{}\">{}</Topology><Geometry GeometryType=\"{}\">{}</Geometry>",
      topo, s.cells[0], hdf_item(base + "cells", s.cells, "Int", 8), dim == 2 ? "XY" : "XYZ",
      hdf_item(base + "nodes", s.nodes, "Float", 8));
  if (!s.sdf.empty()) x += attribute("sdf", "Scalar", hdf_item(base + "point_cloud/sdf", s.sdf, "Float", 8));
  if (!s.dirichlet_distance.empty())
    x += attribute("dirichlet_distance", "Scalar",
                   hdf_item(base + "point_cloud/dirichlet_distance", s.dirichlet_distance, "Float", 8));
  for (const char* f : {"dirichlet_mask", "neumann_mask"})
    x += attribute(f, "Scalar", hdf_item(base + f, {s.nodes[0]}, "Char", 1));
  return x;
}

/// One shape as a temporal collection: load case l is time step l.
std::string shape_xml(const ShapeInfo& s, const std::string& shard_rel, const std::string& views_rel) {
  const std::string fixed = shape_static_xml(s, shard_rel);
  std::string x = fmt::format("<Grid Name=\"shape {}\" GridType=\"Collection\" CollectionType=\"Temporal\">\n", s.name);
  for (hsize_t l = 0; l < std::max<hsize_t>(s.n_loads, 1); ++l) {
    x += fmt::format("<Grid Name=\"shape {} load {}\" GridType=\"Uniform\"><Time Value=\"{}\"/>", s.name, l, l) + fixed;
    for (const auto& [field, d] : s.load_fields)
      x += attribute(field, "Vector",
                     hdf_item(fmt::format("{}:/shapes/{}/{}/{}", views_rel, s.name, field, l), {d[1], d[2]}, "Float", 8));
    x += "</Grid>\n";
  }
  return x + "</Grid>\n";
}

void write_text(const std::string& path, const std::string& body) {
  const std::string tmp = path + fmt::format(".tmp-{}", ::getpid());
  {
    std::ofstream o(tmp);
    o << "<?xml version=\"1.0\" ?>\n<Xdmf Version=\"3.0\">\n<Domain>\n" << body << "</Domain>\n</Xdmf>\n";
    if (!o) throw std::runtime_error("cannot write " + tmp);
  }
  fs::rename(tmp, path);
}

}  // namespace

void write_dataset_xdmf(const std::string& shard_path, const std::string& xdmf_path) {
  const fs::path dir = fs::absolute(xdmf_path).parent_path();
  const std::string shard_rel = fs::relative(fs::absolute(shard_path), dir).string();
  const fs::path views = fs::path(xdmf_path).replace_extension(".h5");
  std::vector<ShapeInfo> shapes;
  {
    Id file{check_id(H5Fopen(shard_path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), "open " + shard_path), H5Fclose};
    shapes = read_shapes(file.id);
  }
  write_views_file(shapes, shard_rel, views.string());
  const std::string views_rel = views.filename().string();
  std::string all = "<Grid Name=\"shapes\" GridType=\"Collection\" CollectionType=\"Spatial\">\n";
  for (const auto& s : shapes) {
    const std::string one = shape_xml(s, shard_rel, views_rel);
    all += one;
    write_text((dir / ("shape-" + s.name + ".xdmf")).string(), one);
  }
  write_text(xdmf_path, all + "</Grid>\n");
}

}  // namespace hypershape::io
