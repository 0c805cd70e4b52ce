#!/usr/bin/env bash
# The main job of the README: install dependencies, build, then run mipnerf-cl.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/install-deps.sh
./scripts/build.sh
build_dir="${BUILD_DIR:-build}"
"$build_dir/mipnerf-cl" devices
