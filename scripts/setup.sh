#!/usr/bin/env bash
# Installs what hypershape needs from Debian 12 (only what is missing), then configures and
# builds it (Release) in ./build. Idempotent: a second run with nothing changed takes seconds.
#   scripts/setup.sh                  # every package + configure + build every target (tests too)
#   scripts/setup.sh hypershape_cli   # the packages a build and its data readers need, and only
#                                     # the targets named (scripts/run.sh: the CLI, about 2 of the 5
#                                     # minutes of a fresh unity build on 2 cores)
#   BUILD_DIR=build-dev BUILD_TYPE=Developer scripts/setup.sh
set -euo pipefail
cd "$(dirname "$0")/.."

# Each package and what it is for (the README's dependency table says the same).
PACKAGES=(
  g++ cmake make pkg-config git     # toolchain
  petsc-dev                         # PETSc 3.18: DMPlex, PetscFE, SNES, KSP; MUMPS, hypre
  libgmsh-dev                       # gmsh C++ API: meshes built in-process
  libmetis-dev                      # METIS: mesh partitions for groups of ranks
  libhdf5-openmpi-dev               # parallel HDF5: results and dataset shards
  libeigen3-dev                     # fixed-size small linear algebra in kernels
  catch2                            # unit-test framework (v2.13)
  openmpi-bin                       # mpiexec
  libmumps-dev                      # MUMPS in single precision (solver.factor_precision: single; PETSc's pulls it in)
  libsuitesparse-dev                # SuiteSparse's AMD: the blocked LDL^T's fill-reducing node ordering (PETSc's pulls it in)
  libopenblas0-serial               # optimised BLAS for MUMPS (4-6x faster factorisations)
  libyaml-cpp-dev                   # scene and dataset files
  libcli11-dev                      # command-line parsing
  libfmt-dev                        # formatting (GCC 12 has no <format>)
  nlohmann-json3-dev                # JSON reports and benchmarks
  libdeflate-dev                    # DEFLATE of the HDF5 arrays' chunks (twice zlib's speed), the shards' CRC-32
  libcgal-dev                       # CGAL: AABB trees (distances), self-intersection checks, surface remeshing
  python3-h5py python3-numpy        # Python readers and checks of the output
  python3-matplotlib                # galleries, histograms and plots in the README
)
# Only for the tests and the torch Datasets: 159 packages, 578 MB installed (torch brings OpenCV,
# Qt, GDAL and FFmpeg's libraries), about a minute of apt on a fresh machine, so a build of named
# targets (scripts/run.sh) leaves them out; scripts/setup.sh without targets (scripts/test.sh)
# installs them.
TEST_PACKAGES=(
  libpetsc3.18-dev-examples         # PETSc's tutorials (reference for the API)
  python3-meshio                    # reads the datasets' XDMF views in a test (tests/python/test_xdmf_views.py)
  python3-torch                     # PyTorch Datasets of the grid and point-cloud forms (scripts/hypershape_torch.py)
  time                              # /usr/bin/time: the CPU seconds of scripts/bench_groups.sh and study_accuracy_levels.sh
)
if [ $# -eq 0 ]; then PACKAGES+=("${TEST_PACKAGES[@]}"); fi

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  if [ "$(id -u)" = 0 ]; then
    echo "[setup] installing: ${missing[*]}"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
  else
    echo "[setup] missing Debian packages. Run as root:"
    echo "  apt-get update && apt-get install -y --no-install-recommends ${missing[*]}"
    exit 1
  fi
fi

BUILD_DIR=${BUILD_DIR:-build}
BUILD_TYPE=${BUILD_TYPE:-Release}
if [ ! -f "$BUILD_DIR/CMakeCache.txt" ]; then
  cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE="$BUILD_TYPE" >/dev/null
fi
# (pipefail: a failed build fails here; grep alone may find nothing to print)
targets=()
for t in "$@"; do targets+=(--target "$t"); done
if ! cmake --build "$BUILD_DIR" -j "$(getconf _NPROCESSORS_ONLN)" "${targets[@]}" 2>&1 | { grep -v "^\[ *[0-9]*%\]" || true; }; then
  echo "[setup] the build failed (messages above)" >&2
  exit 1
fi
echo "[setup] build ready in $BUILD_DIR"
