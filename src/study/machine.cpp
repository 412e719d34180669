#include "hypershape/study/machine.hpp"

#include <petscsys.h>
#include <unistd.h>

#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>

#include "hypershape/core/error.hpp"
#include "hypershape/study/stats.hpp"

namespace hypershape::study {

using nlohmann::json;

json machine_note() {
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

std::array<std::string, 3> load_average() {
  std::ifstream f("/proc/loadavg");
  std::array<std::string, 3> a;
  f >> a[0] >> a[1] >> a[2];
  return a;
}

std::string load_average_text() {
  const auto a = load_average();
  return a[0] + " " + a[1] + " " + a[2];
}

json load_average_json() {
  json out = json::array();
  for (const auto& s : load_average()) {
    double v = NAN;
    try {
      v = std::stod(s);
    } catch (const std::exception&) {
    }
    out.push_back(number_or_null(v));
  }
  return out;
}

}  // namespace hypershape::study
