#!/usr/bin/env bash
# The thread-sanitizer build: clang++ with ThreadSanitizer (MIPNERF_TSAN) in its own build folder
# (${TSAN_BUILD_DIR:-build-tsan}), of only what the tests whose code starts threads need (CTest label `threads`,
# tests/CMakeLists.txt: the viewer's handler and real renderer, `view` through its socket, the scene writers, the host
# MLP's row-block threads in training), then those tests on PoCL's CPU device. Any data race, lock-order inversion or
# thread leak report fails its test. scripts/test.sh calls it with --build-only and runs the tests itself (its `tsan`
# stage); on its own it builds and runs them.
set -euo pipefail
cd "$(dirname "$0")/.."
build_dir="${TSAN_BUILD_DIR:-build-tsan}"
jobs="${JOBS:-$(nproc)}"
export CMAKE_CXX_COMPILER_LAUNCHER="${CMAKE_CXX_COMPILER_LAUNCHER:-$(command -v ccache || true)}"
export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$PWD}"
start=$(date +%s)
# The kernels compiled for the main build's tests serve these tests too (tests/CMakeLists.txt,
# MIPNERF_TEST_POCL_CACHE): same sources, same options, PoCL keys on both.
main_build="${BUILD_DIR:-build}"
case "$main_build" in /*) ;; *) main_build="$PWD/$main_build" ;; esac
pocl_cache="${MIPNERF_TEST_POCL_CACHE:-$main_build/pocl-cache}"
mkdir -p "$pocl_cache"
cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER=clang++ -DMIPNERF_TSAN=ON \
  -DMIPNERF_TEST_POCL_CACHE="$pocl_cache" -DMIPNERF_BUILD_BENCH=OFF -DMIPNERF_MPI=OFF
# The executables of the `threads` tests, and of the fixtures they need (the CLI test trains its run with mipnerf-cl).
cmake --build "$build_dir" -j "$jobs" --target mipnerf-cl test_view test_data test_mlp test_train
built=$(date +%s)
echo "test: thread-sanitizer build $((built - start)) s"
[ "${1:-}" = "--build-only" ] && exit 0
echo "test: the tests that start threads under ThreadSanitizer, on PoCL's CPU device ($build_dir)"
ctest --test-dir "$build_dir" --output-on-failure -j "$jobs" -L '^threads$'
echo "test: thread-sanitizer build $((built - start)) s, its tests $(( $(date +%s) - built )) s"
