#pragma once
/// A range of shapes of a dataset, spread over the ranks of a communicator, gathered on rank 0
/// in shape-id order (what `hypershape shapes` writes). The shapes do not depend on the number
/// of ranks: shape i is always make_shape(config, base, seed, i).
#include <mpi.h>

#include <cstdint>
#include <optional>
#include <vector>

#include "hypershape/config/dataset.hpp"
#include "hypershape/factory/shape_pipeline.hpp"
#include "hypershape/io/shape_file.hpp"

namespace hypershape::factory {

/// The flat record of a shape (for files and for sending between ranks).
io::ShapeRecord to_record(const ShapeSample& s);

/// load_base(config.shapes), with a bad surface file reported as an input error of the config
/// (its file and the key that chose the surface: shapes.base_file or shapes.base_dir). Raised
/// on every rank alike. Not collective.
std::optional<geometry::Boundary> load_dataset_base(const config::DatasetConfig& config);

/// Shapes [first, first + count): rank r draws the ids with (id - first) % size == r and prints
/// a progress line per shape; rank 0 returns all records in id order, other ranks an empty
/// vector. A shape whose every attempt failed becomes a record with `failed` = 1 and its reasons
/// (no crash, nothing missing). Collective over `comm`.
std::vector<io::ShapeRecord> make_shape_range(MPI_Comm comm, const config::DatasetConfig& config,
                                              std::int64_t first, std::int64_t count);

}  // namespace hypershape::factory
