#pragma once
/// The subcommands of the `hypershape` command line, one function each: what
/// drivers/hypershape.cpp calls once it has parsed the arguments. Each validates what it can
/// before any work (core::InputError), prints its summary line(s) and returns the exit status.
#include <mpi.h>

#include <cstdint>
#include <string>

#include "hypershape/config/dataset.hpp"
#include "hypershape/factory/generate.hpp"
#include "hypershape/factory/solve_scene.hpp"

namespace hypershape::factory {

/// `hypershape solve`: one scene (`scene_path`, or the embedded default) to `out` (.h5 + .xdmf).
/// 0 if it converged, 3 if not. Collective.
int run_solve(MPI_Comm comm, const std::string& scene_path, const std::string& out, const SceneRuns& runs);
/// `hypershape shapes`: shapes [first, first + count) of a dataset config to `out`; 3 if any
/// failed. Collective.
int run_shapes(MPI_Comm comm, const std::string& config_path, const std::string& out, std::int64_t first,
               std::int64_t count);
/// `hypershape generate`: the dataset to `out` (default results/<name>). Collective.
int run_generate(MPI_Comm comm, const config::DatasetConfig& cfg, const std::string& out, GenerateOptions gen);
/// `hypershape index`: 0 if the dataset is complete, 4 if shards are missing. Collective.
int run_index(MPI_Comm comm, const std::string& dir);
/// The dataset `generate` makes: a config file, an embedded preset or the default, maybe --mini.
config::DatasetConfig dataset_to_generate(const std::string& config_path, const std::string& preset, bool mini);

}  // namespace hypershape::factory
