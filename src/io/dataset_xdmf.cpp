#include "hypershape/io/dataset_xdmf.hpp"

#include <fmt/format.h>
#include <hdf5.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string_view>

#include "h5_util.hpp"

namespace hypershape::io {

namespace {

namespace fs = std::filesystem;

std::vector<hsize_t> dims_of(hid_t g, const char* name) {
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
  std::vector<hsize_t> d(std::size_t(H5Sget_simple_extent_ndims(sp.id)));
  H5Sget_simple_extent_dims(sp.id, d.data(), nullptr);
  return d;
}

std::string join(const std::vector<hsize_t>& d) {
  std::string s;
  for (auto v : d) s += (s.empty() ? "" : " ") + std::to_string(v);
  return s;
}

std::string hdf_item(const std::string& ref, const std::vector<hsize_t>& d, const char* type, int precision) {
  return fmt::format("<DataItem Dimensions=\"{}\" NumberType=\"{}\" Precision=\"{}\" Format=\"HDF\">{}</DataItem>",
                     join(d), type, precision, ref);
}

/// Row l of a (L x n x c) dataset as an (n x c) item.
std::string slab(const std::string& ref, const std::vector<hsize_t>& d, hsize_t l) {
  return fmt::format(
      "<DataItem ItemType=\"HyperSlab\" Dimensions=\"{} {}\"><DataItem Dimensions=\"3 3\" Format=\"XML\">"
      "{} 0 0 1 1 1 1 {} {}</DataItem>{}</DataItem>",
      d[1], d[2], l, d[1], d[2], hdf_item(ref, d, "Float", 8));
}

}  // namespace

void write_dataset_xdmf(const std::string& shard_path, const std::string& xdmf_path) {
  const std::string h5 = fs::relative(fs::absolute(shard_path), fs::absolute(xdmf_path).parent_path()).string();
  Id file{check_id(H5Fopen(shard_path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), "open " + shard_path), H5Fclose};
  Id all{check_id(H5Gopen2(file.id, "shapes", H5P_DEFAULT), "shapes"), H5Gclose};
  H5G_info_t info;
  check(H5Gget_info(all.id, &info), "shapes");
  std::ostringstream x;
  x << "<?xml version=\"1.0\" ?>\n<Xdmf Version=\"3.0\">\n <Domain>\n"
    << "  <Grid Name=\"shapes\" GridType=\"Collection\" CollectionType=\"Spatial\">\n";
  for (hsize_t i = 0; i < info.nlinks; ++i) {
    char name[64];
    H5Lget_name_by_idx(all.id, ".", H5_INDEX_NAME, H5_ITER_INC, i, name, sizeof name, H5P_DEFAULT);
    Id g{check_id(H5Gopen2(all.id, name, H5P_DEFAULT), name), H5Gclose};
    const auto nd = dims_of(g.id, "nodes"), cd = dims_of(g.id, "cells"), ud = dims_of(g.id, "loads/displacement");
    if (nd.size() != 2 || cd.size() != 2) continue;  // a failed shape: nothing to show
    const hsize_t dim = nd[1], per = cd[1];
    const char* topo = dim == 2 ? (per == 3 ? "Triangle" : "Triangle_6") : (per == 4 ? "Tetrahedron" : "Tetrahedron_10");
    const std::string base = h5 + ":/shapes/" + name + "/";
    const std::string topology = fmt::format(
        "<Topology TopologyType=\"{}\" NumberOfElements=\"{}\">{}</Topology>"
        "<Geometry GeometryType=\"{}\">{}</Geometry>",
        topo, cd[0], hdf_item(base + "cells", cd, "Int", 8), dim == 2 ? "XY" : "XYZ",
        hdf_item(base + "nodes", nd, "Float", 8));
    std::string node_fields;
    for (const char* f : {"point_cloud/sdf", "point_cloud/dirichlet_distance"}) {
      const auto d = dims_of(g.id, f);
      if (!d.empty())
        node_fields += fmt::format("<Attribute Name=\"{}\" AttributeType=\"Scalar\" Center=\"Node\">{}</Attribute>",
                                   fs::path(f).filename().string(), hdf_item(base + f, d, "Float", 8));
    }
    for (const char* f : {"dirichlet_mask", "neumann_mask"})
      node_fields += fmt::format("<Attribute Name=\"{}\" AttributeType=\"Scalar\" Center=\"Node\">{}</Attribute>", f,
                                 hdf_item(base + f, dims_of(g.id, f), "Char", 1));
    x << "   <Grid Name=\"shape " << name << "\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
    const hsize_t n_loads = ud.size() == 3 ? ud[0] : 0;
    const auto td = dims_of(g.id, "loads/traction");
    for (hsize_t l = 0; l < std::max<hsize_t>(n_loads, 1); ++l) {
      x << "    <Grid Name=\"shape " << name << " load " << l << "\" GridType=\"Uniform\"><Time Value=\"" << l
        << "\"/>" << topology << node_fields;
      if (n_loads > 0) {
        x << "<Attribute Name=\"displacement\" AttributeType=\"Vector\" Center=\"Node\">"
          << slab(base + "loads/displacement", ud, l) << "</Attribute>";
        if (td.size() == 3)
          x << "<Attribute Name=\"traction\" AttributeType=\"Vector\" Center=\"Node\">"
            << slab(base + "loads/traction", td, l) << "</Attribute>";
      }
      x << "</Grid>\n";
    }
    x << "   </Grid>\n";
  }
  x << "  </Grid>\n </Domain>\n</Xdmf>\n";
  const std::string tmp = xdmf_path + fmt::format(".tmp-{}", ::getpid());
  {
    std::ofstream o(tmp);
    o << x.str();
    if (!o) throw std::runtime_error("cannot write " + tmp);
  }
  fs::rename(tmp, xdmf_path);
}

}  // namespace hypershape::io
