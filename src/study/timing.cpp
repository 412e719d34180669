#include "hypershape/study/timing.hpp"

#include <malloc.h>

#include <cmath>
#include <ctime>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include "hypershape/core/error.hpp"

namespace hypershape::study {

double cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

LogStage::LogStage(const char* name) {
  static std::map<std::string, PetscLogStage> stages;
  auto it = stages.find(name);
  if (it == stages.end()) {
    PetscLogStage s;
    HS_PETSC(PetscLogStageRegister(name, &s));
    it = stages.emplace(name, s).first;
  }
  HS_PETSC(PetscLogStagePush(it->second));
}

namespace {
/// A "Key:   123 kB" line of /proc/self/status, in MiB.
double proc_status_mib(const std::string& key) {
  std::ifstream f("/proc/self/status");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind(key, 0) == 0) {
      std::istringstream s(line.substr(key.size()));
      double kb = 0;
      s >> kb;
      return kb / 1024.0;
    }
  return NAN;
}
}  // namespace

double resident_mib() { return proc_status_mib("VmRSS:"); }
double peak_resident_mib() { return proc_status_mib("VmHWM:"); }

void reset_peak_resident() {
  malloc_trim(0);
  std::ofstream f("/proc/self/clear_refs");
  f << "5";
}

}  // namespace hypershape::study
