#pragma once
/// The machine a figure was measured on, for the benchmarks' and the study's JSON.
#include <array>
#include <nlohmann/json.hpp>
#include <string>

namespace hypershape::study {

/// Host, cores, CPU model, PETSc version, the BLAS behind libblas.so.3, OPENBLAS_NUM_THREADS
/// and the date (UTC). After PetscInitialize; not collective.
nlohmann::json machine_note();

/// The 1, 5 and 15 minute load averages as /proc/loadavg writes them.
std::array<std::string, 3> load_average();
/// load_average() as "a b c".
std::string load_average_text();
/// load_average() as a JSON array of three numbers (null where unreadable).
nlohmann::json load_average_json();

}  // namespace hypershape::study
