#pragma once
/// `hypershape generate`: a dataset from a config, on any number of ranks and SLURM tasks.
///
/// Plan: shapes [0, N) in shards of `shard_size` consecutive shapes; shard k belongs to SLURM
/// task k mod task_count. Schedule: the ranks split into solver groups of `group_size`; groups
/// take the task's unfinished shards one at a time from a shared counter (MPI one-sided
/// fetch-and-add on rank 0), so a hard shape holds up only its own group. Every value stored is
/// a function of (seed, shape id, load id): the dataset does not depend on ranks, groups or
/// tasks. A shard is written under a temporary name and renamed when complete; a rerun skips
/// complete shards and redoes the rest (resume after a kill).
///
/// Output directory:
///   dataset.yaml                     the resolved config (a rerun with another config stops)
///   shards/shard-NNNNNN.h5           the data (docs/FORMAT.md)
///   reports/task-I-of-N.json         run report per task: counts, phases, memory
///   manifest.json, splits.json, stats.json   written by the index step (dataset_index.hpp),
///   xdmf/shard-NNNNNN.xdmf           run automatically once every shard exists
#include <mpi.h>

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "hypershape/config/dataset.hpp"
#include "hypershape/factory/accuracy.hpp"
#include "hypershape/factory/label_error.hpp"
#include "hypershape/factory/solve_counters.hpp"

namespace hypershape::factory {

struct GenerateOptions {
  std::string output_dir;
  int task_index = 0, task_count = 1;  ///< SLURM array slice
  int group_size = 1;                  ///< ranks per shape
  double progress_seconds = 10;        ///< interval of the progress line (0: none)
  bool force = false;                  ///< write a dataset above the size bound / the free space
  /// PETSc options given on the command line (names with one dash), checked before any work.
  std::vector<std::string> petsc_command_line;
};

struct RunReport {
  std::int64_t shards_total = 0, shards_done_before = 0, shards_written = 0;
  std::int64_t shapes = 0, shapes_failed = 0;
  SolveCounters counters;  ///< summed over the run's load cases
  double seconds = 0;
  std::map<std::string, double> phase_seconds;  ///< summed over group roots
  double factorization_seconds = 0;             ///< PCSetUp, summed over ranks
  LabelErrorSummary label_error;  ///< the labels' error estimates over the converged load cases
  config::AccuracyConfig accuracy_config;  ///< the dataset's accuracy: block (off: no accuracy report)
  AccuracySummary accuracy;       ///< what the accuracy ladder chose and what it cost
  std::string json;                              ///< the report as written (rank 0)
  bool indexed = false;                          ///< manifest written (dataset complete)
};

/// Collective over `comm`. Throws core::InputError (before anything is written) for bad PETSc
/// options, a dataset too large for the bound or the free space (unless options.force), an
/// unusable output directory, one that holds another dataset (by meaning:
/// config::canonical_text), or one another run is writing (factory::OutputLock). A resume keeps
/// only the shards that pass verification (factory::shard_problem) and redoes the rest.
RunReport generate(MPI_Comm comm, const config::DatasetConfig& config, const GenerateOptions& options);

/// The report as a short table (rank 0).
std::string report_table(const RunReport& report);

/// Shard file name of shard k.
std::string shard_name(std::int64_t k);

}  // namespace hypershape::factory
