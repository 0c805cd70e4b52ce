#!/usr/bin/env bash
# The README's main job: install dependencies, build, make the built-in procedural scene, tune the GEMMs for
# this device where CLBlast runs them (once, 2-4 minutes; skipped on CPU devices that use the host BLAS), train the `quick`
# preset on it (ending with val PSNR, training time and render s/MP), then render an orbit around it.
# Re-running continues where it stopped (train --resume) instead of starting over.
# Each phase says how long it took, and the last line sums them up, with the time until training's first step
# (the figures of README.md's "Quick start" come from here).
set -euo pipefail
cd "$(dirname "$0")/.."
build_dir="${BUILD_DIR:-build}"
runs="${RUNS_DIR:-runs}"

summary=""
now_ms() { echo $(($(date +%s%N) / 1000000)); }
started_at=$(now_ms)
seconds_since() { echo $((($(now_ms) - $1 + 500) / 1000)); }  # whole seconds since a now_ms time
# timed NAME COMMAND...: runs the command, then says how long it took and adds it to the summary.
timed() {
  local name=$1 start
  shift
  start=$(now_ms)
  "$@"
  local took
  took=$(seconds_since "$start")
  echo "quickstart: $name took ${took}s"
  summary+="$name ${took}s, "
}

timed install ./scripts/install-deps.sh
timed configure ./scripts/build.sh --configure-only
timed build ./scripts/build.sh mipnerf-cl  # the executable alone; the test suites build with the test command
timed scene "$build_dir/mipnerf-cl" make-scene "$runs/scene"
# Where CLBlast runs the MLP (GPUs, or gemm_backend=clblast) its default GEMM parameters are slow: a short,
# time-boxed tune once per device is worth it. On a CPU device using the host BLAS (auto) it says so and skips.
timed tune "$build_dir/mipnerf-cl" tune --minutes 4 --if-missing
# On a CPU device the host MLP can run each product on OpenBLAS, BLIS, oneDNN or libxsmm: about a minute, once per
# device, times them on the presets' products and keeps the fastest per product (docs/training.md).
timed tune-host "$build_dir/mipnerf-cl" tune --host-gemm --if-missing
# Training's first progress line comes after its first step: the time until then is the wait before it is under way.
train_started_at=$(now_ms)
first_step_file=$(mktemp)
trap 'rm -f "$first_step_file"' EXIT
timed train ./scripts/time_to_output.py "$first_step_file" "train [" -- \
  "$build_dir/mipnerf-cl" train --data "$runs/scene" --out "$runs/quick" --preset quick --resume
timed render "$build_dir/mipnerf-cl" render --checkpoint "$runs/quick" --path orbit --frames 24 --format both
echo "quickstart: val renders in $runs/quick/val, the orbit in $runs/quick/render_orbit, figures in $runs/quick/summary.json"

if [ -s "$first_step_file" ]; then
  to_first_step=$(((train_started_at - started_at + $(cat "$first_step_file") + 500) / 1000))
  first_step="training's first step after ${to_first_step}s, "
else
  first_step=""  # a resumed run that had no steps left draws no progress line
fi
echo "quickstart: ${summary}${first_step}all $(seconds_since "$started_at")s ($(nproc) cores)"
