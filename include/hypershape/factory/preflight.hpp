#pragma once
/// Everything `generate` checks before it writes a byte: the dataset's size and time (a rough
/// estimate, printed; a refusal above a sane bound or above the free space of the output file
/// system unless forced), and the PETSc options (a trial set-up and solve on a coarse disk or
/// ball with the dataset's scene, degree and solver options: an option PETSc rejects, or one
/// nothing asked for, is an input error naming it).
#include <mpi.h>

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "hypershape/config/dataset.hpp"
#include "hypershape/geometry/boundary.hpp"

namespace hypershape::factory {

/// A rough size and cost of a dataset, from its mesh size, degree, grids and counts. In 2D the
/// mesh is that of shape 0, drawn and meshed here (0.1-0.5 s): a 2D boundary is resolved by its
/// curvature, so the vertex count follows the shape more than h (Random2D at h 0.12: 1.7k
/// vertices where a uniform mesh of h would have 0.2k). In 3D, from h (a draw costs seconds).
struct DatasetEstimate {
  double nodes_per_shape = 0;
  double bytes_per_shape = 0;      ///< compressed, as stored
  double cpu_seconds_per_load = 0;
  double bytes = 0, cpu_seconds = 0;  ///< the whole dataset (accuracy: every label at level 0)
  /// A dataset asked for by accuracy: a typical load case's CPU seconds at ladder level 1, 2, ...
  std::vector<double> cpu_seconds_per_resolve;
  /// "about 1.2 GB on disk and 3h20m of CPU ..." (and what a label solved again costs).
  std::string line() const;
};
DatasetEstimate estimate_dataset(const config::DatasetConfig& cfg, const std::optional<geometry::Boundary>& base);

/// A dataset above this many bytes needs --force.
inline constexpr double max_dataset_bytes = 1024.0 * 1024 * 1024 * 1024;

/// Throws core::InputError (file, "shapes.count") when `bytes_to_write` exceeds
/// max_dataset_bytes or the free space of the file system that will hold `output_dir`, unless
/// `force`. Not collective; writes nothing.
void check_resources(const config::DatasetConfig& cfg, const DatasetEstimate& e, double bytes_to_write,
                     const std::string& output_dir, bool force);

/// Before each shard (group roots): throws io::StorageError, before HDF5 opens anything, when
/// the file system of `output_dir` has less than half of `shard_bytes` (the estimate) free.
void check_shard_space(const std::string& output_dir, std::int64_t shard, double shard_bytes);

/// Human units: "1.2 GB", "3h20m".
std::string format_bytes(double bytes);
std::string format_duration(double seconds);

/// A PETSc option the user gave and where: "petsc.<key>" of the config file, or the command line.
struct UserOption {
  std::string name;    ///< with the dash: "-pc_type"
  std::string origin;  ///< "petsc.pc_type" or "command line"
};
/// The config's petsc: block followed by `command_line` (names with one dash).
std::vector<UserOption> user_options(const config::DatasetConfig& cfg, const std::vector<std::string>& command_line);

/// Sets the config's options (the command line wins), then sets up and solves the dataset's
/// scene once on a coarse disk (2D) or ball (3D) on PETSC_COMM_SELF, output to the terminal as
/// PETSc prints it. Throws core::InputError if PETSc rejects an option or one of `options` was
/// never asked for. Every rank runs it alike (no collective).
void check_petsc_options(const config::DatasetConfig& cfg, const std::vector<UserOption>& options);

}  // namespace hypershape::factory
