#include "hypershape/core/log.hpp"

#include <cstdio>

namespace hypershape::core {

namespace {
Verbosity g_verbosity = Verbosity::normal;
}

void set_verbosity(Verbosity v) { g_verbosity = v; }
Verbosity verbosity() { return g_verbosity; }

void log_line(MPI_Comm comm, Verbosity level, std::string_view line) {
  if (level > g_verbosity) return;
  int r = 0;
  MPI_Comm_rank(comm, &r);
  if (r != 0) return;
  std::fwrite(line.data(), 1, line.size(), stdout);
  std::fputc('\n', stdout);
  std::fflush(stdout);
}

}  // namespace hypershape::core
