#!/usr/bin/env bash
# The README's main job: install dependencies, build, make the built-in procedural scene, tune the GEMMs for
# this device where CLBlast runs them (once, 2-4 minutes; skipped on CPU devices that use the host BLAS), train the `quick`
# preset on it (ending with val PSNR, training time and render s/MP), then render an orbit around it.
# Re-running continues where it stopped (train --resume) instead of starting over.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/install-deps.sh
./scripts/build.sh mipnerf-cl  # the executable alone; the test suites build with the test command
build_dir="${BUILD_DIR:-build}"
runs="${RUNS_DIR:-runs}"
"$build_dir/mipnerf-cl" make-scene "$runs/scene"
# Where CLBlast runs the MLP (GPUs, or gemm_backend=clblast) its default GEMM parameters are slow: a short,
# time-boxed tune once per device is worth it. On a CPU device using the host BLAS (auto) it says so and skips.
"$build_dir/mipnerf-cl" tune --minutes 4 --if-missing
# On a CPU device the host MLP can run each product on OpenBLAS, BLIS, oneDNN or libxsmm: about a minute, once per
# device, times them on the presets' products and keeps the fastest per product (docs/training.md).
"$build_dir/mipnerf-cl" tune --host-gemm --if-missing
"$build_dir/mipnerf-cl" train --data "$runs/scene" --out "$runs/quick" --preset quick --resume
"$build_dir/mipnerf-cl" render --checkpoint "$runs/quick" --path orbit --frames 24 --format both
echo "quickstart: val renders in $runs/quick/val, the orbit in $runs/quick/render_orbit, figures in $runs/quick/summary.json"
