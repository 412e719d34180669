#pragma once
/// One shape's geometry as an HDF5 group (boundary, mesh, Dirichlet facets, redraws, metrics),
/// shared by shape sets and dataset shards (internal to src/io/).
#include <hdf5.h>

#include "hypershape/io/shape_file.hpp"

namespace hypershape::io {

void write_shape_group(hid_t group, const ShapeRecord& shape);
ShapeRecord read_shape_group(hid_t group);

}  // namespace hypershape::io
