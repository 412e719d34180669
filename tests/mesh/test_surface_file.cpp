/// read_surface_file: ASCII STL, binary STL and gmsh .msh surfaces read to the same closed
/// outward surface; bad files are InputErrors naming the file and the problem, and gmsh keeps
/// working after them.
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include "geometry/shapes.hpp"
#include "hypershape/core/input_error.hpp"
#include "hypershape/geometry/boundary_check.hpp"
#include "hypershape/mesh/surface_file.hpp"

using namespace hypershape;
using Catch::Contains;
using geometry::Boundary;

namespace {

namespace fs = std::filesystem;

/// A fresh, empty temporary directory for this test file (removed at the end of the process).
struct TempDir {
  fs::path dir;
  TempDir() {
    dir = fs::temp_directory_path() / ("hypershape_surface_file_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(dir, ec);
  }
  std::string operator/(const std::string& name) const { return (dir / name).string(); }
};
const TempDir& tmp() {
  static TempDir t;
  return t;
}

double volume(const Boundary& b) {
  double v6 = 0;
  for (std::int64_t f = 0; f < b.n_facets(); ++f) {
    const double* a = &b.points[3 * std::size_t(b.facets[3 * f])];
    const double* c = &b.points[3 * std::size_t(b.facets[3 * f + 1])];
    const double* d = &b.points[3 * std::size_t(b.facets[3 * f + 2])];
    v6 += a[0] * (c[1] * d[2] - c[2] * d[1]) - a[1] * (c[0] * d[2] - c[2] * d[0]) +
          a[2] * (c[0] * d[1] - c[1] * d[0]);
  }
  return v6 / 6;
}

void write_ascii_stl(const std::string& path, const Boundary& b) {
  std::ofstream out(path);
  out.precision(17);
  out << "solid test\n";
  for (std::int64_t f = 0; f < b.n_facets(); ++f) {
    out << "  facet normal 0 0 0\n    outer loop\n";
    for (int v : b.facet(f)) {
      const auto p = b.point(v);
      out << "      vertex " << p[0] << ' ' << p[1] << ' ' << p[2] << '\n';
    }
    out << "    endloop\n  endfacet\n";
  }
  out << "endsolid test\n";
}

void write_binary_stl(const std::string& path, const Boundary& b) {
  std::ofstream out(path, std::ios::binary);
  char header[80] = {};
  std::strncpy(header, "binary STL written by test_surface_file", sizeof header - 1);
  out.write(header, 80);
  const std::uint32_t n = std::uint32_t(b.n_facets());
  out.write(reinterpret_cast<const char*>(&n), 4);
  for (std::int64_t f = 0; f < b.n_facets(); ++f) {
    float data[12] = {};
    int k = 3;
    for (int v : b.facet(f))
      for (double x : b.point(v)) data[k++] = float(x);
    out.write(reinterpret_cast<const char*>(data), sizeof data);
    const std::uint16_t attr = 0;
    out.write(reinterpret_cast<const char*>(&attr), 2);
  }
}

/// MSH 2.2 (ASCII) with scattered node tags, an unused node, and the triangles split over two
/// surface entities.
void write_msh(const std::string& path, const Boundary& b) {
  std::ofstream out(path);
  out.precision(17);
  out << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n" << b.n_points() + 1 << '\n';
  for (std::int64_t i = 0; i < b.n_points(); ++i) {
    const auto p = b.point(i);
    out << 7 + 3 * i << ' ' << p[0] << ' ' << p[1] << ' ' << p[2] << '\n';
  }
  out << 5 << " 9 9 9\n$EndNodes\n$Elements\n" << b.n_facets() << '\n';
  for (std::int64_t f = 0; f < b.n_facets(); ++f) {
    const int entity = f < b.n_facets() / 2 ? 1 : 2;
    out << f + 1 << " 2 2 " << entity << ' ' << entity;
    for (int v : b.facet(f)) out << ' ' << 7 + 3 * v;
    out << '\n';
  }
  out << "$EndElements\n";
}

/// Reads `path` expecting an InputError; returns its message.
std::string read_error(const std::string& path) {
  try {
    mesh::read_surface_file(path);
  } catch (const core::InputError& e) {
    CHECK(e.file() == path);
    CHECK_THAT(e.what(), Contains(path));
    return e.what();
  }
  FAIL("no InputError for " << path);
  return {};
}

}  // namespace

TEST_CASE("read_surface_file reads ASCII STL, binary STL and .msh alike", "[mesh]") {
  const Boundary sphere = geometry::test::icosphere(2);  // 162 points, 320 triangles
  const double v_exact = volume(sphere);

  write_ascii_stl(tmp() / "sphere_ascii.stl", sphere);
  write_binary_stl(tmp() / "sphere_binary.STL", sphere);
  write_msh(tmp() / "sphere.msh", sphere);

  for (const std::string name : {"sphere_ascii.stl", "sphere_binary.STL", "sphere.msh"}) {
    INFO(name);
    const Boundary s = mesh::read_surface_file(tmp() / name);
    CHECK(s.dim == 3);
    CHECK(s.n_points() == sphere.n_points());
    CHECK(s.n_facets() == sphere.n_facets());
    CHECK(volume(s) == Approx(v_exact).epsilon(1e-6));  // float STL: 1e-7 relative
    CHECK(geometry::check_boundary(s).ok);
  }
}

TEST_CASE("read_surface_file orients an inward surface outward", "[mesh]") {
  Boundary inward = geometry::test::icosphere(1);
  for (std::size_t f = 0; f < inward.facets.size(); f += 3)
    std::swap(inward.facets[f + 1], inward.facets[f + 2]);
  write_ascii_stl(tmp() / "inward.stl", inward);
  const Boundary s = mesh::read_surface_file(tmp() / "inward.stl");
  CHECK(volume(s) > 0);
  CHECK(volume(s) == Approx(-volume(inward)));
}

TEST_CASE("read_surface_file rejects bad files with InputError and keeps gmsh usable", "[mesh]") {
  const Boundary sphere = geometry::test::icosphere(2);
  const std::string good = tmp() / "good.stl";
  write_ascii_stl(good, sphere);

  SECTION("missing") { CHECK_THAT(read_error(tmp() / "missing.stl"), Contains("does not exist")); }
  SECTION("unsupported extension") {
    const std::string path = tmp() / "sphere.obj";
    std::ofstream(path) << "v 0 0 0\n";
    CHECK_THAT(read_error(path), Contains("unsupported surface file extension '.obj'"));
  }
  SECTION("garbage text") {
    const std::string path = tmp() / "garbage.stl";
    std::ofstream(path) << "this is not an STL file\n1 2 3\n";
    const std::string msg = read_error(path);
    CHECK((msg.find("could not read") != std::string::npos ||
           msg.find("no triangles") != std::string::npos));
  }
  SECTION("garbage .msh") {
    const std::string path = tmp() / "garbage.msh";
    std::ofstream(path) << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\nnonsense\n";
    const std::string msg = read_error(path);
    CHECK((msg.find("could not read") != std::string::npos ||
           msg.find("no triangles") != std::string::npos));
  }
  SECTION("open surface") {
    Boundary open = sphere;
    open.facets.resize(open.facets.size() - 3);
    write_ascii_stl(tmp() / "open.stl", open);
    CHECK_THAT(read_error(tmp() / "open.stl"),
               Contains("not a valid closed surface: open surface: 3 boundary edges"));
  }
  SECTION("self-intersecting") {
    Boundary pushed = sphere;
    for (int k = 0; k < 3; ++k) pushed.points[k] *= -1.5;  // point 0 through the far side
    write_binary_stl(tmp() / "pushed.stl", pushed);
    CHECK_THAT(read_error(tmp() / "pushed.stl"), Contains("self-intersecting surface"));
  }
  SECTION("two components") {
    Boundary two = sphere;
    for (std::int64_t i = 0; i < sphere.n_points(); ++i) {
      const auto p = sphere.point(i);
      two.points.insert(two.points.end(), {p[0] + 3, p[1], p[2]});
    }
    for (int v : sphere.facets) two.facets.push_back(v + int(sphere.n_points()));
    write_ascii_stl(tmp() / "two.stl", two);
    CHECK_THAT(read_error(tmp() / "two.stl"), Contains("2 connected components"));
  }
  SECTION("quadrangles") {
    const std::string path = tmp() / "quads.msh";
    std::ofstream(path) << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0\n2 1 0 0\n"
                           "3 1 1 0\n4 0 1 0\n$EndNodes\n$Elements\n1\n1 3 2 1 1 1 2 3 4\n"
                           "$EndElements\n";
    CHECK_THAT(read_error(path), Contains("1 quadrangles"));
  }
  // Whatever failed above, the next read works.
  const Boundary s = mesh::read_surface_file(good);
  CHECK(s.n_facets() == sphere.n_facets());
}
