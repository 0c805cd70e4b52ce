#!/usr/bin/env bash
# Configures and builds mipnerf-cl (Release) into ${BUILD_DIR:-build}: every target, or only the targets named
# (scripts/quickstart.sh builds the executable alone). --configure-only: the configure step alone (the quick start
# times it apart from the build).
set -euo pipefail
cd "$(dirname "$0")/.."
build_dir="${BUILD_DIR:-build}"
jobs="${JOBS:-$(nproc)}"
# ccache, when installed, keeps rebuilds after a checkout switch short (scripts/test-sanitize.sh does the same).
export CMAKE_CXX_COMPILER_LAUNCHER="${CMAKE_CXX_COMPILER_LAUNCHER:-$(command -v ccache || true)}"
# Paths below the checkout hash as relative ones, so a clean checkout elsewhere reuses the cache.
export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$PWD}"
cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release
if [ "${1:-}" = "--configure-only" ]; then
  exit 0
elif [ $# -gt 0 ]; then
  cmake --build "$build_dir" -j "$jobs" --target "$@"
else
  cmake --build "$build_dir" -j "$jobs"
fi
