// The numerics platform string: which of glibc's libm paths a process takes, from the CPU and
// GLIBC_TUNABLES (measured: masking FMA or AVX2 switches log/exp/sin/cos to the AVX or SSE2
// variants, whose results differ from the FMA ones in the last bits; README, "On machines of
// different kinds").
#include <catch2/catch.hpp>

#include <string>

#include "hypershape/core/platform.hpp"

using hypershape::core::libm_fma_path;

TEST_CASE("glibc's FMA path is taken unless the CPU lacks it or the tunables mask it", "[platform]") {
  CHECK(libm_fma_path(nullptr, true));
  CHECK_FALSE(libm_fma_path(nullptr, false));
  CHECK_FALSE(libm_fma_path("glibc.cpu.hwcaps=-FMA", true));
  CHECK_FALSE(libm_fma_path("glibc.cpu.hwcaps=-AVX2", true));
  CHECK_FALSE(libm_fma_path("glibc.cpu.hwcaps=-AVX2_Usable,-FMA_Usable", true));
  CHECK_FALSE(libm_fma_path("glibc.malloc.check=3:glibc.cpu.hwcaps=-SSE4_1,-FMA", true));
  CHECK(libm_fma_path("glibc.cpu.hwcaps=-SSE4_1", true));     // another feature
  CHECK(libm_fma_path("glibc.cpu.hwcaps=-FMA4", true));       // AMD's FMA4: not the FMA path's
  CHECK(libm_fma_path("glibc.malloc.check=3", true));         // another tunable
  CHECK_FALSE(libm_fma_path("glibc.cpu.hwcaps=-FMA", false));
}

TEST_CASE("the numerics platform names glibc's libm path and the BLAS", "[platform]") {
  const std::string s = hypershape::core::numerics_platform();
  INFO(s);
  CHECK(s.rfind("glibc ", 0) == 0);
  CHECK((s.find(" libm fma; ") != std::string::npos || s.find(" libm no-fma; ") != std::string::npos));
  CHECK((s.find("OpenBLAS ") != std::string::npos || s.find("BLAS without a kernel name") != std::string::npos));
}
