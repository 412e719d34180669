#pragma once
/// Which code paths this process's numerics take where libraries choose them at run time by CPU:
/// glibc's libm (an FMA variant of log, exp, sin, cos, ... on CPUs with FMA and AVX2, whose last
/// bits differ from the AVX and SSE2 variants) and OpenBLAS (kernels per CPU family). Two runs
/// with the same string make the same data bit for bit; with different strings the data agree to
/// round-off, and a shape may mesh differently (README, "On machines of different kinds").
#include <string>

namespace hypershape::core {

/// E.g. "glibc 2.36 libm fma; OpenBLAS Cooperlake". Stored in each shard (`software/numerics`)
/// and in the run report; `hypershape index` warns when a dataset's shards differ in it.
std::string numerics_platform();

/// Whether glibc's libm takes its FMA variants in a process started with the environment
/// variable GLIBC_TUNABLES = `tunables` (nullptr: unset) on a CPU with (or without) FMA and AVX2:
/// both usable and neither masked by `glibc.cpu.hwcaps` (`-FMA`, `-AVX2`, `-AVX`, or their
/// older `_Usable` names).
bool libm_fma_path(const char* tunables, bool cpu_has_fma_and_avx2);

}  // namespace hypershape::core
