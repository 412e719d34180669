#pragma once
/// The arrays of one shape in a dataset shard, in one table (name, dimensions, per shape or per
/// load case, units, meaning). run_shape takes every array's meaning and units from it,
/// docs/FORMAT.md lists every name (tests/factory/test_dataset_schema.cpp checks both ways), and
/// the readers see the table's meaning and units as each array's attributes.
#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "hypershape/io/dataset_shard.hpp"

namespace hypershape::factory {

struct SchemaEntry {
  std::string_view name;     ///< path in the shape's group; "<...>" marks a pattern part
  std::string_view dims;     ///< e.g. "n x d", "L x N^d x d" (n nodes, L load cases, N grid points per axis)
  std::string_view per;      ///< "shape" or "load case"
  std::string_view units;    ///< the "units" attribute ("" dimensionless or an index)
  std::string_view meaning;  ///< the "meaning" attribute
};

/// Every array run_shape writes for a solved shape (the shape record's own arrays, boundary/,
/// mesh/, dirichlet_facets, rejected, are the shape sets' layout: io/shape_file.hpp).
const std::vector<SchemaEntry>& shard_schema();

/// The entry for `name`: exact, or the pattern entry it matches ("params/<label>/<key>").
/// Throws std::logic_error for a name not in the table (a bug: add it to the table).
const SchemaEntry& schema_entry(const std::string& name);

/// An array of the table, its meaning and units from the entry.
template <class T>
io::Array schema_array(const std::string& name, std::vector<std::uint64_t> shape, std::vector<T> data) {
  const SchemaEntry& e = schema_entry(name);
  return {name, std::move(shape), std::move(data), std::string(e.meaning), std::string(e.units)};
}

}  // namespace hypershape::factory
