#!/usr/bin/env bash
# The test command of the README and of CI: install dependencies, build, run the whole suite.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/install-deps.sh
./scripts/build.sh
build_dir="${BUILD_DIR:-build}"
ctest --test-dir "$build_dir" --output-on-failure -j "${JOBS:-$(nproc)}"
