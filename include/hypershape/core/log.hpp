#pragma once
/// One logger for library output: rank 0 of the given communicator prints, others stay quiet.
#include <fmt/format.h>
#include <mpi.h>

#include <string_view>

namespace hypershape::core {

enum class Verbosity { quiet = 0, normal = 1, debug = 2 };

/// Global verbosity (set by drivers from -hs_verbosity / --quiet).
void set_verbosity(Verbosity v);
Verbosity verbosity();

/// Prints a line on rank 0 of `comm` (not collective).
void log_line(MPI_Comm comm, Verbosity level, std::string_view line);

template <class... Args>
void info(MPI_Comm comm, fmt::format_string<Args...> f, Args&&... args) {
  log_line(comm, Verbosity::normal, fmt::format(f, std::forward<Args>(args)...));
}
template <class... Args>
void debug(MPI_Comm comm, fmt::format_string<Args...> f, Args&&... args) {
  if (verbosity() >= Verbosity::debug)
    log_line(comm, Verbosity::debug, fmt::format(f, std::forward<Args>(args)...));
}

}  // namespace hypershape::core
