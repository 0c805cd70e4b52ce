#!/usr/bin/env bash
# The sanitizer build: the whole suite built with clang++ under AddressSanitizer + UndefinedBehaviorSanitizer
# (MIPNERF_SANITIZE) together with the fuzz targets (MIPNERF_FUZZ), in one extra build folder
# (${SANITIZE_BUILD_DIR:-build-sanitize}), then run on PoCL's CPU device: every test but the `oclgrind` ones (the
# normal build runs those), the fuzz targets' short entries (label `fuzz`) included. Any sanitizer report fails its
# test. scripts/test.sh calls it with --build-only and runs the tests itself (its `sanitizer` and `fuzz` stages); on its
# own it builds and runs them.
set -euo pipefail
cd "$(dirname "$0")/.."
build_dir="${SANITIZE_BUILD_DIR:-build-sanitize}"
jobs="${JOBS:-$(nproc)}"
export CMAKE_CXX_COMPILER_LAUNCHER="${CMAKE_CXX_COMPILER_LAUNCHER:-$(command -v ccache || true)}"
# Paths below the checkout hash as relative ones, so a clean checkout elsewhere reuses the cache.
export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$PWD}"
start=$(date +%s)
# The kernels compiled for the main build's tests serve these tests too (tests/CMakeLists.txt,
# MIPNERF_TEST_POCL_CACHE): same sources, same options, PoCL keys on both.
main_build="${BUILD_DIR:-build}"
case "$main_build" in /*) ;; *) main_build="$PWD/$main_build" ;; esac
pocl_cache="${MIPNERF_TEST_POCL_CACHE:-$main_build/pocl-cache}"
mkdir -p "$pocl_cache"
# No bench programs here: no test runs them, and the plain build compiles them.
cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER=clang++ -DMIPNERF_SANITIZE=ON -DMIPNERF_FUZZ=ON \
  -DMIPNERF_TEST_POCL_CACHE="$pocl_cache" -DMIPNERF_BUILD_BENCH=OFF -DMIPNERF_MPI=OFF  # MPI is tested in the plain build; here, a build without it (refused under mpirun)
cmake --build "$build_dir" -j "$jobs"
built=$(date +%s)
echo "test: sanitizer build $((built - start)) s"
[ "${1:-}" = "--build-only" ] && exit 0
echo "test: the whole suite under AddressSanitizer + UBSan, and the fuzz targets, on PoCL's CPU device ($build_dir)"
ctest --test-dir "$build_dir" --output-on-failure -j "$jobs" -LE oclgrind
echo "test: sanitizer build $((built - start)) s, its tests $(( $(date +%s) - built )) s"
