#!/usr/bin/env bash
# The test command of the README and of CI: install dependencies, build, run the whole suite on every OpenCL
# implementation we test on (PoCL, then Intel's CPU runtime when it can be installed) and once more built with
# AddressSanitizer + UBSan together with the fuzz targets; fails if any run fails. SANITIZE=0 leaves out the
# sanitizer build (the plain runs alone).
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/install-deps.sh
./scripts/build.sh
build_dir="${BUILD_DIR:-build}"
jobs="${JOBS:-$(nproc)}"

# 1. PoCL's CPU device (the tests' default: the first CPU device), and the kernel tests under oclgrind (label
#    `oclgrind`). Day to day, `ctest --test-dir build -j2 -LE oclgrind` is the quick run on PoCL alone.
echo "test: the whole suite on PoCL's CPU device, and the kernel tests under oclgrind"
ctest --test-dir "$build_dir" --output-on-failure -j "$jobs"

# 2. The sanitizer build (its own build folder, clang++): the suite under AddressSanitizer + UBSan on PoCL, but the
#    oclgrind tests (run above), and each fuzz target for 20 s (label `fuzz`). scripts/test-sanitize.sh.
if [ "${SANITIZE:-1}" != 0 ]; then
  ./scripts/test-sanitize.sh
fi

# 3. Intel's CPU OpenCL runtime, a second, independent implementation (installed into a cache folder from PyPI).
#    MIPNERF_TEST_DEVICE picks the tests' device, MIPNERF_DEVICE the executable's (the CLI tests).
if environment="$(./scripts/install-intel-opencl.sh)"; then
  eval "$environment"
  echo "test: the whole suite on Intel's CPU OpenCL runtime ($OCL_ICD_VENDORS)"
  MIPNERF_TEST_DEVICE=Intel MIPNERF_DEVICE=Intel ctest --test-dir "$build_dir" --output-on-failure -j "$jobs" -LE oclgrind
else
  echo "test: Intel's CPU OpenCL runtime could not be installed (above); the PoCL run decides"
fi
