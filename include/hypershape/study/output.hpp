#pragma once
/// What the benchmark and study drivers share: their command line (our options before "--",
/// PETSc's after), their JSON output (written under a temporary name, then renamed, so a
/// killed run never leaves a partial file) and the way their tables print a time.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace hypershape::study {

/// An argument vector: argv[0] first and a null pointer after the last argument (argv[argc] ==
/// NULL: MPI_Init walks argv to it; without it Open MPI read past the end and crashed).
struct Argv {
  std::vector<char*> args{nullptr};
  int count() const { return int(args.size()) - 1; }
  char** data() { return args.data(); }
  char** begin() { return args.data(); }
  char** end() { return args.data() + count(); }  ///< the arguments only, not the null pointer
  void push_back(char* a) { args.insert(args.end() - 1, a); }
};
/// argv split at the first "--": `ours` and `petsc`, each starting with argv[0].
struct SplitArgs {
  Argv ours, petsc;
};
SplitArgs split_at_dashes(int argc, char** argv);

/// Checks, before any work, that `path` can be written (creates its directory, opens and
/// removes `path`.tmp): an unwritable output is reported on stderr as an error naming the
/// path and `option` and the driver exits (2) instead of losing its results at the end. An
/// empty path (no output) passes.
bool output_writable(const std::string& path, const std::string& option);

/// Writes `j` to `path` (creating its directory) through `path`.tmp and a rename. `option`
/// names the command-line option the path came from, for the error message (core::InputError).
void write_json_atomic(const std::string& path, const nlohmann::json& j, const std::string& option, int indent = 2);

/// Seconds as the benchmark tables print them: "12us", "3.4ms", "1.23s", "123s"; "-" if not finite.
std::string format_seconds(double s);
/// A count (or a median of counts) rounded to the nearest integer, halves away from zero; "-" if
/// not finite.
std::string format_count(double v);

}  // namespace hypershape::study
