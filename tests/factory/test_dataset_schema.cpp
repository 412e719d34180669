// The shard schema is one table (factory::shard_schema): docs/FORMAT.md lists every name in it
// with the same units, and names resolve to their entries, patterns included.
#include <catch2/catch.hpp>

#include <algorithm>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "hypershape/factory/dataset_schema.hpp"

using namespace hypershape;

namespace {

/// The rows of FORMAT.md's tables: cells split at '|', trimmed.
std::vector<std::vector<std::string>> format_rows() {
  std::ifstream in(std::string(HS_SOURCE_DIR) + "/docs/FORMAT.md");
  REQUIRE(in);
  std::vector<std::vector<std::string>> rows;
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("| `", 0) != 0) continue;
    std::vector<std::string> cells;
    std::stringstream ss(line.substr(1));
    for (std::string c; std::getline(ss, c, '|');) {
      const auto a = c.find_first_not_of(' '), b = c.find_last_not_of(' ');
      cells.push_back(a == std::string::npos ? "" : c.substr(a, b - a + 1));
    }
    rows.push_back(cells);
  }
  return rows;
}

}  // namespace

TEST_CASE("FORMAT.md lists every array of the shard schema, with its units", "[factory][schema]") {
  const auto rows = format_rows();
  for (const auto& e : factory::shard_schema()) {
    const std::string quoted = "`" + std::string(e.name) + "`";
    INFO(e.name);
    const std::vector<std::string>* row = nullptr;
    for (const auto& r : rows)
      if (r.size() >= 3 && r[0].find(quoted) != std::string::npos) row = &r;
    REQUIRE(row != nullptr);
    // One name per row: its units column is the attribute the writer stores.
    if (std::count((*row)[0].begin(), (*row)[0].end(), '`') == 2) CHECK((*row)[2] == e.units);
  }
}

TEST_CASE("array names resolve to their schema entries", "[factory][schema]") {
  CHECK(factory::schema_entry("loads/alpha").units == "force");
  CHECK(factory::schema_entry("params/neo_hookean/E").name == "params/<label>/<key>");
  CHECK(factory::schema_entry("params/gaussian_traction.2/gamma").name == "params/<label>/<key>");
  CHECK(factory::schema_entry("params/gaussian_traction.1/center").units == "length");
  CHECK(factory::schema_entry("stats/grid_body_force").name == "stats/<field>");
  CHECK_THROWS_AS(factory::schema_entry("loads/magnetic_field"), std::logic_error);
  const auto a = factory::schema_array("loads/target", {3}, std::vector<double>{0.1, 0.2, 0.3});
  CHECK(a.units == "length");
  CHECK(a.meaning == "wanted max|u|");
}
