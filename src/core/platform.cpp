#include "hypershape/core/platform.hpp"

#include <dlfcn.h>
#include <gnu/libc-version.h>

#include <cstdlib>
#include <sstream>

namespace hypershape::core {

bool libm_fma_path(const char* tunables, bool cpu_has_fma_and_avx2) {
  if (!cpu_has_fma_and_avx2) return false;
  if (!tunables) return true;
  // GLIBC_TUNABLES is a colon-separated list of name=value; hwcaps' value a comma-separated list.
  const std::string all(tunables), key = "glibc.cpu.hwcaps=";
  std::istringstream items(all);
  for (std::string item; std::getline(items, item, ':');) {
    if (item.rfind(key, 0) != 0) continue;
    std::istringstream caps(item.substr(key.size()));
    for (std::string cap; std::getline(caps, cap, ',');)
      for (const char* masked : {"-FMA", "-FMA_Usable", "-AVX2", "-AVX2_Usable", "-AVX", "-AVX_Usable"})
        if (cap == masked) return false;
  }
  return true;
}

std::string numerics_platform() {
  __builtin_cpu_init();
  const bool fma = __builtin_cpu_supports("fma") && __builtin_cpu_supports("avx2");
  std::string s = std::string("glibc ") + gnu_get_libc_version() + " libm " +
                  (libm_fma_path(std::getenv("GLIBC_TUNABLES"), fma) ? "fma" : "no-fma");
  // OpenBLAS names the kernel family it picked (OPENBLAS_CORETYPE overrides it); another BLAS
  // behind libblas.so.3 has no such call.
  using CoreName = char* (*)();
  if (auto* name = reinterpret_cast<CoreName>(dlsym(RTLD_DEFAULT, "openblas_get_corename")))
    s += std::string("; OpenBLAS ") + name();
  else
    s += "; BLAS without a kernel name";
  return s;
}

}  // namespace hypershape::core
