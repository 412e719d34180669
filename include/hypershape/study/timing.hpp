#pragma once
/// Timing and memory probes of the benchmarks and the accuracy study: CPU time, collective wall
/// time of a call, a PETSc log stage per measured phase (so -log_view splits a run the same
/// way), and the resident-set probes of /proc/self.
#include <mpi.h>
#include <petscsys.h>

#include "hypershape/core/timer.hpp"

namespace hypershape::study {

/// Process CPU time in seconds (what contention on a shared machine inflates far less than wall
/// time). Not collective.
double cpu_seconds();

/// Wall time of `f` in seconds, with every rank of `comm` lined up before and after (collective).
template <class F>
double timed(MPI_Comm comm, F&& f) {
  MPI_Barrier(comm);
  const double t0 = core::now_seconds();
  f();
  MPI_Barrier(comm);
  return core::now_seconds() - t0;
}

/// A PETSc log stage pushed for a scope (registered once per name). Collective, as the stages.
class LogStage {
 public:
  explicit LogStage(const char* name);
  ~LogStage() { PetscLogStagePop(); }
  LogStage(const LogStage&) = delete;
  LogStage& operator=(const LogStage&) = delete;
};

/// Resident set now (VmRSS), MiB; NaN where /proc/self/status has no such line.
double resident_mib();
/// Peak resident set (VmHWM) since the start or the last reset_peak_resident(), MiB.
double peak_resident_mib();
/// Returns freed heap to the system, then resets the peak resident set (VmHWM) to the current
/// one (Linux >= 4.0), so that VmHWM afterwards is the peak of what runs in between.
void reset_peak_resident();

}  // namespace hypershape::study
