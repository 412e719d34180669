/// hypershape: the command-line entry point.
///
///   hypershape solve [SCENE.yaml] -o OUT.h5     one scene (default: the embedded one);
///                                               --targets/--repeat: several load cases (benchmarks)
///   hypershape shapes CONFIG.yaml -o SHAPES.h5  random shapes of a dataset config (meshes,
///                                               Dirichlet patches, metrics); MPI-parallel
///   hypershape generate [DATASET.yaml] [-o DIR]  a dataset (default: the embedded small one;
///                                               --preset NAME: a preset; --mini: a few shapes);
///                                               MPI solver groups, SLURM arrays, resume
///   hypershape index DIR                        manifest, splits, statistics, XDMF of a dataset
///   hypershape effects                          lists the effects a scene may use
///
/// PETSc options (-snes_monitor, -pc_type ..., -log_view) pass through to PETSc. This file parses
/// the command line; each subcommand is one call into factory/commands.hpp.
#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstdlib>

#include "hypershape/core/error.hpp"
#include "hypershape/core/log.hpp"
#include "hypershape/core/petsc_handle.hpp"
#include "hypershape/core/interrupt.hpp"
#include "hypershape/factory/commands.hpp"
#include "hypershape/io/dataset_shard.hpp"
#include "hypershape/physics/registry.hpp"
#include "hypershape/solver/nonlinear.hpp"

using namespace hypershape;

namespace {

/// The PETSc option names among the arguments CLI11 left (`-name [value]`); anything else is
/// an input error (a misspelt `--option`, a stray word), named before any work. Any subcommand.
std::vector<std::string> petsc_option_names(const std::vector<std::string>& extras) {
  std::vector<std::string> names;
  bool value_allowed = false;
  for (const auto& a : extras) {
    const bool number = !a.empty() && (std::isdigit(static_cast<unsigned char>(a[0])) || a[0] == '.' ||
                                       (a.size() > 1 && a[0] == '-' && (std::isdigit(static_cast<unsigned char>(a[1])) || a[1] == '.')));
    if (a.rfind("--", 0) == 0)
      throw core::InputError("", a, "unknown option (see `hypershape SUBCOMMAND --help`; PETSc options take one dash)");
    if (a.size() > 1 && a[0] == '-' && !number) {
      names.push_back(a);
      value_allowed = true;
    } else if (value_allowed) {
      value_allowed = false;  // the value of the PETSc option before it
    } else {
      throw core::InputError("", a, "unexpected argument (see `hypershape SUBCOMMAND --help`)");
    }
  }
  return names;
}

/// CLI11 reads `-options_left` as `-o ptions_left` (a short option with its value attached):
/// single-dash words that start with a letter of a short option of ours (-o, -q, -n) and go on
/// are PETSc options; they and their value (the next word, unless it is an option) are taken out
/// of the arguments CLI11 sees and returned. `args` is argv without argv[0].
std::vector<std::string> take_petsc_lookalikes(std::vector<std::string>& args) {
  std::vector<std::string> kept, taken;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const auto& a = args[i];
    if (a.size() > 2 && a[0] == '-' && (a[1] == 'o' || a[1] == 'q' || a[1] == 'n')) {
      taken.push_back(a);
      if (i + 1 < args.size() && args[i + 1][0] != '-') taken.push_back(args[++i]);
    } else {
      kept.push_back(a);
    }
  }
  args = kept;
  return taken;
}

struct SolveArgs {
  std::string scene, out = "solution.h5";
  factory::SceneRuns runs;
};
struct ShapesArgs {
  std::string config, out = "shapes.h5";
  std::int64_t first = 0, count = -1;
};
struct GenerateArgs {
  std::string config, out, preset;
  bool mini = false;
  factory::GenerateOptions options;
};

CLI::App* add_solve(CLI::App& app, SolveArgs& a) {
  auto* solve = app.add_subcommand("solve", "solve one scene and write it to HDF5 + XDMF");
  solve->add_option("scene", a.scene, "scene file (YAML); default: the embedded default scene");
  solve->add_option("-o,--output", a.out, "output file (.h5); an .xdmf file is written beside it");
  solve->add_option("--targets", a.runs.targets,
                    "benchmarks: solve these targets (max|u|) in turn instead of load.target, each "
                    "from rest on the same solver; each one's seconds, alpha, ... in /timings/")
      ->delimiter(',')
      ->check(CLI::Range(1e-12, 2.0));
  solve->add_option("--repeat", a.runs.repeat, "benchmarks: solve the load case(s) N times")->check(CLI::PositiveNumber);
  solve->allow_extras();
  return solve;
}

CLI::App* add_shapes(CLI::App& app, ShapesArgs& a) {
  auto* shapes = app.add_subcommand("shapes", "draw and mesh the random shapes of a dataset config");
  shapes->add_option("config", a.config, "dataset config (YAML), e.g. configs/presets/random2d.yaml")->required();
  shapes->add_option("-o,--output", a.out, "output file (.h5)");
  shapes->add_option("--first", a.first, "first shape id")->check(CLI::NonNegativeNumber);
  shapes->add_option("-n,--count", a.count, "number of shapes (default: shapes.count - first)");
  shapes->allow_extras();
  return shapes;
}

int env_int(const char* name, int fallback) {
  const char* v = std::getenv(name);
  return v && *v ? std::atoi(v) : fallback;
}

CLI::App* add_generate(CLI::App& app, GenerateArgs& a) {
  auto* generate = app.add_subcommand("generate", "generate a dataset (shards, manifest, splits, statistics)");
  factory::GenerateOptions& gen = a.options;
  // SLURM array defaults: the task's offset in the array and the array's size.
  gen.task_index = env_int("SLURM_ARRAY_TASK_ID", 0) - env_int("SLURM_ARRAY_TASK_MIN", 0);
  gen.task_count = env_int("SLURM_ARRAY_TASK_COUNT", 1);
  auto* config = generate->add_option("config", a.config, "dataset config (YAML); default: the embedded small dataset");
  generate->add_option("--preset", a.preset, "an embedded preset (configs/presets/NAME.yaml) instead of a config")
      ->excludes(config);
  generate->add_flag("--mini", a.mini,
                     "a few shapes and load cases of it (<= 4 shapes in 2D, 2 in 3D; 2 load cases, 4 for one "
                     "shape; coarse grids): seconds, for docs and loaders; named NAME_mini");
  generate->add_option("-o,--output", a.out, "output directory (default: results/<name>)");
  generate->add_option("--task-index", gen.task_index, "this task's slice (default: $SLURM_ARRAY_TASK_ID - $SLURM_ARRAY_TASK_MIN)");
  generate->add_option("--task-count", gen.task_count, "number of slices (default: $SLURM_ARRAY_TASK_COUNT or 1)");
  generate->add_option("--group-size", gen.group_size, "ranks per shape (default 1)");
  generate->add_option("--progress", gen.progress_seconds, "seconds between progress lines (0: none)");
  generate->add_flag("--force", gen.force, "write a dataset above the size bound (1 TB) or the free disk space");
  generate->allow_extras();
  return generate;
}

int run(int argc, char** argv) {
  MPI_Comm comm = PETSC_COMM_WORLD;
  const int rank = core::rank(comm);
  CLI::App app{"hypershape: hyperelastic finite-element data factory"};
  app.allow_extras();  // PETSc options
  app.fallthrough();   // -q after the subcommand too
  app.require_subcommand(1);
  bool quiet = false;
  app.add_flag("-q,--quiet", quiet, "print only errors");
  SolveArgs solve_args;
  ShapesArgs shapes_args;
  GenerateArgs gen;
  std::string index_dir;
  add_solve(app, solve_args);
  auto* shapes = add_shapes(app, shapes_args);
  auto* generate = add_generate(app, gen);
  auto* index = app.add_subcommand("index", "write the manifest, splits, statistics and XDMF of a dataset directory");
  index->add_option("dir", index_dir, "dataset directory")->required();
  index->allow_extras();
  auto* effects = app.add_subcommand("effects", "list the effects a scene may use");
  effects->allow_extras();

  std::vector<std::string> args(argv + 1, argv + argc);
  const std::vector<std::string> lookalikes = take_petsc_lookalikes(args);
  std::reverse(args.begin(), args.end());  // CLI11 takes a vector last argument first
  try {
    app.parse(args);
  } catch (const CLI::ParseError& e) {
    if (rank == 0) app.exit(e);
    return e.get_exit_code() == 0 ? 0 : 2;
  }
  core::set_verbosity(quiet ? core::Verbosity::quiet : core::Verbosity::normal);
  if (*effects) {
    for (auto& [name, help] : physics::registered_effects()) core::info(comm, "{:20s} {}", name, help);
    return 0;
  }
  // What CLI11 left are PETSc options; a misspelt --option or a stray word stops every subcommand.
  std::vector<std::string> extras = app.remaining(true);
  extras.insert(extras.end(), lookalikes.begin(), lookalikes.end());
  const std::vector<std::string> petsc_names = petsc_option_names(extras);
  if (*generate) {
    gen.options.petsc_command_line = petsc_names;  // checked by a trial solve before any work
    return factory::run_generate(comm, factory::dataset_to_generate(gen.config, gen.preset, gen.mini), gen.out,
                                 gen.options);
  }
  if (*index) {
    core::install_interrupt_handlers("index", rank);  // a manifest being replaced is removed
    return factory::run_index(comm, index_dir);
  }
  if (*shapes) return factory::run_shapes(comm, shapes_args.config, shapes_args.out, shapes_args.first, shapes_args.count);
  return factory::run_solve(comm, solve_args.scene, solve_args.out, solve_args.runs);  // the one subcommand left
}

/// What `-help` (PETSc's) prints first: the project's own settings are YAML keys, not PETSc
/// options; the solver's with their defaults.
std::string petsc_help_intro() {
  const solver::SolverOptions d;
  return fmt::format(
      "hypershape: hyperelastic finite-element data factory; `hypershape --help` lists its subcommands.\n"
      "Its own settings are YAML keys of a scene or dataset config, not PETSc options (README: Scenes, "
      "Datasets); every key is validated.\n"
      "  solver:  rtol {:g}, max_newton {}, max_increments {}, target_rtol {:g}, control displacement|load "
      "({}), path_rtol {:g},\n"
      "           newton_budget {}, fallback {}, branch_switches {}, step_growth {:g} (0: by dimension), "
      "abandon_off_path {}, absolute_pivots {},\n"
      "           factor_reuse {}, krylov_budget {} (0: by dimension), krylov_rtol {:g},\n"
      "           linear auto|direct|gamg|hypre ({}; auto: gamg in 3D from linear_auto_dofs {} unknowns)\n"
      "  petsc:   any PETSc option listed below, without the dash (the command line wins)\n"
      "  `hypershape effects` lists the effects a scene may use.\n",
      d.rtol, d.max_newton, d.max_increments, d.target_rtol,
      d.control == solver::Control::displacement ? "displacement" : "load", d.path_rtol, d.newton_budget,
      d.fallback, d.branch_switches, d.step_growth, d.abandon_off_path, d.absolute_pivots, d.tangent.reuse,
      d.tangent.krylov_budget,
      d.tangent.krylov_rtol,
      solver::to_string(d.tangent.linear), d.tangent.auto_dofs);
}

}  // namespace

int main(int argc, char** argv) {
  const std::string help = petsc_help_intro();
  core::PetscSession session(&argc, &argv, help.c_str());
  int code = 1;
  try {
    code = run(argc, argv);
  } catch (const core::InputError& e) {
    // Input errors are raised on every rank alike: report once.
    if (core::rank(PETSC_COMM_WORLD) == 0) std::fprintf(stderr, "error: %s\n", e.what());
    code = 2;
  } catch (const io::StorageError& e) {
    // The shard's temporary file is gone; HDF5 may still hold it and crash in its shutdown
    // (PetscFinalize -> MPI_Finalize -> HDF5): end here, with the message, the status and no crash.
    std::fprintf(stderr, "[rank %d] error: %s\n", core::rank(PETSC_COMM_WORLD), e.what());
    std::fflush(nullptr);
    if (core::size(PETSC_COMM_WORLD) > 1) MPI_Abort(PETSC_COMM_WORLD, 1);
    std::_Exit(1);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "[rank %d] error: %s\n", core::rank(PETSC_COMM_WORLD), e.what());
    code = 1;
    // Other ranks may wait in a collective for this one: stop them all.
    if (core::size(PETSC_COMM_WORLD) > 1) MPI_Abort(PETSC_COMM_WORLD, code);
  }
  return code;
}
