#pragma once
/// What the benchmark and study drivers share: their command line (our options before "--",
/// PETSc's after) and their JSON output (written under a temporary name, then renamed, so a
/// killed run never leaves a partial file), and the note on the machine they ran on.
#include <petscsys.h>
#include <unistd.h>

#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "hypershape/core/error.hpp"
#include "hypershape/core/input_error.hpp"

namespace hypershape::drivers {

/// argv split at the first "--": `ours` and `petsc`, each starting with argv[0].
struct SplitArgs {
  std::vector<char*> ours, petsc;
};

inline SplitArgs split_at_dashes(int argc, char** argv) {
  SplitArgs s{{argv[0]}, {argv[0]}};
  bool after = false;
  for (int i = 1; i < argc; ++i) {
    if (!after && std::string(argv[i]) == "--") {
      after = true;
      continue;
    }
    (after ? s.petsc : s.ours).push_back(argv[i]);
  }
  return s;
}

/// Checks, before any work, that `path` can be written (creates its directory, opens and
/// removes `path`.tmp): an unwritable output is reported on stderr as an error naming the
/// path and `option` and the driver exits (2) instead of losing its results at the end. An
/// empty path (no output) passes.
inline bool output_writable(const std::string& path, const std::string& option) {
  if (path.empty()) return true;
  const std::filesystem::path p(path);
  std::error_code ec;
  if (p.has_parent_path()) std::filesystem::create_directories(p.parent_path(), ec);
  const std::string tmp = path + ".tmp";
  if (!std::ofstream(tmp)) {
    std::cerr << "error: " << path << ": " << option << ": cannot open for writing\n";
    return false;
  }
  std::filesystem::remove(tmp, ec);
  return true;
}

/// Writes `j` to `path` (creating its directory) through `path`.tmp and a rename. `option`
/// names the command-line option the path came from, for the error message.
inline void write_json_atomic(const std::string& path, const nlohmann::json& j, const std::string& option,
                              int indent = 2) {
  const std::filesystem::path p(path);
  if (p.has_parent_path()) std::filesystem::create_directories(p.parent_path());
  const std::string tmp = path + ".tmp";
  {
    std::ofstream f(tmp);
    if (!f) throw core::InputError(path, option, "cannot open for writing");
    f << j.dump(indent) << "\n";
  }
  std::filesystem::rename(tmp, path);
}

/// The machine a figure was measured on: host, cores, CPU model, PETSc version, the BLAS behind
/// libblas.so.3 and OPENBLAS_NUM_THREADS, and the date (UTC).
inline nlohmann::json machine_note() {
  using nlohmann::json;
  json m;
  char host[256] = {0};
  gethostname(host, sizeof(host) - 1);
  m["hostname"] = host;
  m["nproc"] = long(sysconf(_SC_NPROCESSORS_ONLN));
  std::ifstream cpu("/proc/cpuinfo");
  std::string line;
  while (std::getline(cpu, line))
    if (line.rfind("model name", 0) == 0) {
      m["cpu_model"] = line.substr(line.find(':') + 2);
      break;
    }
  char version[256];
  HS_PETSC(PetscGetVersion(version, sizeof(version)));
  m["petsc_version"] = version;
  std::error_code ec;
  auto blas = std::filesystem::canonical("/etc/alternatives/libblas.so.3-x86_64-linux-gnu", ec);
  m["libblas_so_3"] = ec ? json(nullptr) : json(blas.string());
  const char* obt = std::getenv("OPENBLAS_NUM_THREADS");
  m["OPENBLAS_NUM_THREADS"] = obt ? json(obt) : json(nullptr);
  std::time_t now = std::time(nullptr);
  char buf[64];
  std::strftime(buf, sizeof(buf), "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&now));
  m["date_utc"] = buf;
  return m;
}

}  // namespace hypershape::drivers
