#!/usr/bin/env bash
# The one prepared check of a lent GPU machine (docs/devices.md, "A session lent a GPU"), run from a bundle
# (scripts/bundle.sh) in one device call of at most 10 minutes, within --budget seconds (default 480):
#   driver            find the NVIDIA OpenCL driver (libnvidia-opencl.so*), write an ICD file for it into a folder
#                     that OCL_ICD_VENDORS names, put its folder on the library path; GPU facts from nvidia-smi
#   devices           mipnerf-cl devices
#   selftest          mipnerf-selftest, every check, on that device
#   tune              mipnerf-cl tune --minutes M: CLBlast's parameters for the MLP's products on this GPU (time-boxed)
#   bench-quick       mipnerf-cl bench: GEMM GFLOP/s (CLBlast default and tuned), each kernel, the quick preset's steps
#   bench-small       the small preset's training steps and stage profile
#   bench-paper       the paper preset's at batch 4096 (--paper-batch)
#   zipnerf           Zip-NeRF's s/step on the built-in scene, 20 steps of each candidate for a GPU preset: the CPU's
#                     `fast` preset (one point per interval), with the 6 multisamples, then larger batches and the
#                     official hash size (the atomic scatter a GPU uses), and Zip-NeRF's proposal pipeline
#   python            the python that runs the official code: its JAX and devices; gin-config from the carried wheels
#                     when it lacks it
#   official-default  the official google/mipnerf training step at the paper's configuration, with JAX's default
#                     matmul precision (TF32 on the GPU) (bench/studies/official_step.py)
#   official-float32  the same with jax_default_matmul_precision = float32
#   train             mipnerf-cl train --preset quick on the built-in scene for --train-steps steps, then its val score
#   render            an orbit of 24 frames of that run
# Every step runs under its own time limit (timeout), so one slow step cannot lose the rest; the steps before the
# official ones leave it --official-reserve seconds. Steps that need OpenCL are skipped when `devices` failed.
# Always writes, under --out ($OUT by default; at most 8 files, the device tool's limit): summary.md (each step's
# status, seconds and limit, and its key figures), summary.json, log.txt (every step's output), bench.json (the
# presets' bench.json records), official.json (both precisions' records) and artifacts.tar.gz (bench.md files,
# the self-test's JUnit file, the tuning file, the run's config, logs, val images and orbit frames).
#
# On a GPU machine, from the repository root with the prepared folder carried (scripts/prepare-device-check.sh):
#   scripts/device-check.sh
# The rehearsal on this machine's PoCL, with JAX on the CPU from a local virtual environment:
#   scripts/device-check.sh --opencl pocl --python ~/.cache/mipnerf-cl/vs-official-venv/bin/python \
#       --time-scale 4 --paper-batch 1024 --official-steps 2 --train-steps 100 --render-size 64x64 \
#       --gemm-rows 16384 --out DIR
#
# Options (defaults in brackets):
#   --carried DIR        the prepared folder holding bundle/, official/ and wheels/ [.device-check]
#   --bundle DIR         the bundle [CARRIED/bundle]        --official DIR   google/mipnerf at 84c969e [CARRIED/official]
#   --wheels DIR         wheels installed when the python lacks gin [CARRIED/wheels]
#   --out DIR            results [$OUT, else device-check-out]
#   --opencl KIND        nvidia: find and register NVIDIA's driver; pocl: this machine's PoCL through an ICD file of
#                        our own; system: the system's /etc/OpenCL/vendors as it is [nvidia]
#   --device SELECTOR    the OpenCL device [platform=NVIDIA; platform=Portable Computing Language with --opencl pocl]
#   --python PY          the python with JAX that runs the official code [python3]
#   --budget SECONDS     the whole check's wall time [480]
#   --time-scale F       multiplies every step's limit and the budget (a rehearsal on a CPU) [1]
#   --official-reserve S seconds the earlier steps leave to the official ones [150]
#   --tune-minutes M     tune's time box [1]
#   --paper-batch N      rays per step of the paper preset and of the official step [4096]
#   --official-steps N   timed official steps per precision [10]
#   --train-steps N      steps of the quick training run [600, the preset's]
#   --render-size WxH    the orbit's frame size [256x256]
#   --gemm-rows N        rows of bench-quick's GEMM products [65536, bench's default]
#   --only STEP,...      run these steps only           --skip STEP,...   leave these out
set -uo pipefail
cd "$(dirname "$0")/.."
repo="$PWD"
arguments="$*"
all_steps="driver devices selftest tune bench-quick bench-small bench-paper zipnerf python official-default official-float32 train render"
opencl_steps=" devices selftest tune bench-quick bench-small bench-paper zipnerf train render "

carried=.device-check
bundle="" official="" wheels=""
out="${OUT:-$repo/device-check-out}"
opencl=nvidia
device=""
python=python3
budget=480
scale=1
official_reserve=150
tune_minutes=1
paper_batch=4096
official_steps=10
train_steps=600
render_size=256x256
gemm_rows=65536
only=""
skip=""
while [ $# -gt 0 ]; do
  case "$1" in
    --carried) carried="$2" ;;
    --bundle) bundle="$2" ;;
    --official) official="$2" ;;
    --wheels) wheels="$2" ;;
    --out) out="$2" ;;
    --opencl) opencl="$2" ;;
    --device) device="$2" ;;
    --python) python="$2" ;;
    --budget) budget="$2" ;;
    --time-scale) scale="$2" ;;
    --official-reserve) official_reserve="$2" ;;
    --tune-minutes) tune_minutes="$2" ;;
    --paper-batch) paper_batch="$2" ;;
    --official-steps) official_steps="$2" ;;
    --train-steps) train_steps="$2" ;;
    --render-size) render_size="$2" ;;
    --gemm-rows) gemm_rows="$2" ;;
    --only) only="$2" ;;
    --skip) skip="$2" ;;
    -h|--help) sed -n '2,/^set -uo/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
    *) echo "device-check: unknown option '$1' (--help lists them)" >&2; exit 2 ;;
  esac
  [ $# -ge 2 ] || { echo "device-check: $1 needs a value" >&2; exit 2; }
  shift 2
done
case "$opencl" in nvidia|pocl|system) ;; *) echo "device-check: --opencl nvidia, pocl or system, not '$opencl'" >&2; exit 2 ;; esac
for name in ${only//,/ } ${skip//,/ }; do
  case " $all_steps " in *" $name "*) ;; *) echo "device-check: no step '$name' (steps: $all_steps)" >&2; exit 2 ;; esac
done
absolute() { (cd "$1" 2>/dev/null && pwd) || echo "$1"; }
bundle="$(absolute "${bundle:-$carried/bundle}")"
official="$(absolute "${official:-$carried/official}")"
wheels="$(absolute "${wheels:-$carried/wheels}")"
if [ -z "$device" ]; then
  case "$opencl" in
    nvidia) device="platform=NVIDIA" ;;
    pocl) device="platform=Portable Computing Language" ;;
  esac
fi
mkdir -p "$out" || exit 1
out="$(absolute "$out")"
scaled() { awk -v s="$1" -v f="$scale" 'BEGIN { printf "%d", s * f + 0.5 }'; }

started=$(date +%s)
deadline=$((started + $(scaled "$budget")))
reserve=$(scaled "$official_reserve")
work="$(mktemp -d "${TMPDIR:-/tmp}/device-check.XXXXXX")"
mkdir -p "$work/artifacts" "$work/vendors" "$work/bench" "$work/official" "$work/cache"
log="$out/log.txt"
: > "$log"
: > "$work/steps.tsv"
: > "$work/facts.tsv"
opencl_problem=""

# The environment every step sees: our tuning file in the work folder (not the user's cache), JAX without its
# up-front grab of GPU memory, python unbuffered, our device.
export XDG_CACHE_HOME="$work/cache" POCL_CACHE_DIR="$work/pocl-cache" XLA_PYTHON_CLIENT_PREALLOCATE=false \
  PYTHONUNBUFFERED=1 TF_CPP_MIN_LOG_LEVEL=1
[ -n "$device" ] && export MIPNERF_DEVICE="$device"

fact() { printf '%s\t%s\n' "$1" "$2" >> "$work/facts.tsv"; }
say() { echo "device-check: $*"; echo "device-check: $*" >> "$log"; }
wanted() {
  if [ -n "$only" ]; then case ",$only," in *",$1,"*) ;; *) return 1 ;; esac; fi
  case ",$skip," in *",$1,"*) return 1 ;; esac
}
# record NAME STATUS EXIT SECONDS LIMIT NOTE: one row of the summary.
record() {
  printf '%s\t%s\t%s\t%s\t%s\t%s\n' "$1" "$2" "$3" "$4" "$5" "$6" >> "$work/steps.tsv"
  say "$(printf '%-17s %-9s %7s s (limit %s s)%s' "$1" "$2" "$4" "$5" "${6:+  $6}")"
}

# run_step NAME LIMIT UNTIL FUNCTION [ARGS...]: FUNCTION in a child bash under timeout, with
# min(LIMIT x time scale, UNTIL - now) seconds; its output goes to the log.
run_step() {
  local name="$1" limit until="$3" rc status note="" t0 t1 left
  limit=$(scaled "$2")
  shift 3
  if ! wanted "$name"; then record "$name" skipped - 0 "$limit" "left out (--only/--skip)"; return 0; fi
  if [ -n "$opencl_problem" ] && [[ "$opencl_steps" == *" $name "* ]]; then
    record "$name" skipped - 0 "$limit" "no OpenCL device: $opencl_problem"
    return 0
  fi
  left=$((until - $(date +%s)))
  [ "$left" -lt "$limit" ] && limit=$left
  if [ "$limit" -lt 10 ]; then record "$name" skipped - 0 "$limit" "no time left in the budget"; return 0; fi
  printf '\n===== %s (limit %s s): %s\n' "$name" "$limit" "$*" >> "$log"
  t0=$(date +%s.%N)
  # Every function goes with it (a step's function may call a shared one, e.g. built_in_scene).
  timeout --kill-after=10 "$limit" bash -c "$(declare -f); $(printf '%q ' "$@")" >> "$log" 2>&1
  rc=$?
  t1=$(date +%s.%N)
  case $rc in
    0) status=ok ;;
    124|137) status=timeout; note="stopped at its limit" ;;
    *) status=failed; note="exit $rc" ;;
  esac
  record "$name" "$status" "$rc" "$(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.1f", b - a }')" "$limit" "$note"
  return $rc
}

# ---- driver: the OpenCL implementation, found and registered in this shell (later steps inherit it) ----

# first_existing GLOB...: the first path that exists.
first_existing() { local f; for f in "$@"; do [ -e "$f" ] && { echo "$f"; return 0; }; done; return 1; }

# find_library NAME: NAME (e.g. libnvidia-opencl.so.1) in the driver folders, the loader's cache, else a bounded search.
find_library() {
  local name="$1" stem="${1%%.so*}" found d
  for d in /usr/local/nvidia/lib64 /usr/local/nvidia/lib /usr/lib/x86_64-linux-gnu /lib/x86_64-linux-gnu /usr/lib64 \
      /lib64 /usr/lib /usr/local/cuda/compat /usr/local/cuda/lib64 /usr/lib/wsl/lib; do
    found="$(first_existing "$d/$name" "$d/$stem".so.*)" && { echo "$found"; return 0; }
  done
  found="$(ldconfig -p 2>/dev/null | awk -v n="$stem.so" 'index($1, n) == 1 {print $NF}' | head -n 1)"
  [ -n "$found" ] && { echo "$found"; return 0; }
  found="$(timeout 20 find /usr /opt /lib /lib64 /run -maxdepth 6 -name "$stem.so*" 2>/dev/null | head -n 1)"
  [ -n "$found" ] && { echo "$found"; return 0; }
  return 1
}

driver_step() {
  local t0 t1 status=ok note="" library="" folder cuda
  t0=$(date +%s.%N)
  printf '\n===== driver (--opencl %s)\n' "$opencl" >> "$log"
  {
    echo "uname: $(uname -srm); $(getconf GNU_LIBC_VERSION 2>/dev/null); $(. /etc/os-release 2>/dev/null && echo "$PRETTY_NAME")"
    echo "cpus: $(nproc); memory: $(awk '/MemTotal/ {print $2 / 1048576 " GiB"}' /proc/meminfo)"
    echo "existing ICD files: $(ls /etc/OpenCL/vendors 2>/dev/null | tr '\n' ' ')"
    for f in /etc/OpenCL/vendors/*.icd; do [ -e "$f" ] && echo "  $f: $(cat "$f")"; done
    command -v nvidia-smi > /dev/null && timeout 20 nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.sm,clocks.max.sm,power.limit,temperature.gpu --format=csv
  } >> "$log" 2>&1
  fact machine "$(uname -srm), $(getconf GNU_LIBC_VERSION 2>/dev/null), $(. /etc/os-release 2>/dev/null && echo "$PRETTY_NAME"), $(nproc) CPUs"
  command -v nvidia-smi > /dev/null &&
    fact gpu "$(timeout 20 nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader 2>/dev/null | head -n 1)"
  case "$opencl" in
    nvidia)
      if library="$(find_library libnvidia-opencl.so.1)"; then
        folder="$(dirname "$library")"
        echo "$library" > "$work/vendors/nvidia.icd"
        export OCL_ICD_VENDORS="$work/vendors"
        export LD_LIBRARY_PATH="$folder${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
        # libcuda.so.1, which the OpenCL driver loads, where it is not beside it.
        if cuda="$(find_library libcuda.so.1)" && [ "$(dirname "$cuda")" != "$folder" ]; then
          export LD_LIBRARY_PATH="$(dirname "$cuda"):$LD_LIBRARY_PATH"
        fi
        {
          echo "NVIDIA OpenCL driver: $library; ICD file $work/vendors/nvidia.icd; LD_LIBRARY_PATH=$LD_LIBRARY_PATH"
          ls -la "$folder" | grep -E 'libnvidia|libcuda' | head -40
          echo "its libraries (ldd):"
          ldd "$library"
        } >> "$log" 2>&1
        note="$library"
      else
        status=failed
        note="no libnvidia-opencl.so* in the driver folders, the loader's cache or /usr /opt /lib /lib64 /run"
        opencl_problem="the NVIDIA OpenCL driver (libnvidia-opencl.so*) was not found"
        { echo "$note"; echo "what /usr/local/nvidia holds:"; find /usr/local/nvidia -maxdepth 3 2>/dev/null | head -60; } >> "$log"
      fi ;;
    pocl)
      if library="$(find_library libpocl.so.2)"; then
        echo "$library" > "$work/vendors/pocl.icd"
        export OCL_ICD_VENDORS="$work/vendors"
        note="$library"
      else
        status=failed; note="no libpocl.so.2 here (Debian: pocl-opencl-icd)"; opencl_problem="PoCL was not found"
      fi ;;
    system) note="the system's ICD files (/etc/OpenCL/vendors)" ;;
  esac
  echo "OCL_ICD_VENDORS=${OCL_ICD_VENDORS:-(unset)}" >> "$log"
  fact opencl_driver "$note"
  t1=$(date +%s.%N)
  record driver "$status" - "$(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.1f", b - a }')" - "$note"
}

# ---- the steps (each runs in a child bash: only exported variables reach it) ----
export BUNDLE="$bundle" OFFICIAL="$official" WORK="$work" REPO="$repo" PYTHON="$python" PAPER_BATCH="$paper_batch" \
  OFFICIAL_STEPS="$official_steps" TRAIN_STEPS="$train_steps" TUNE_MINUTES="$tune_minutes" RENDER_SIZE="$render_size"

devices() { "$BUNDLE/mipnerf-cl" devices; }
selftest() { "$BUNDLE/mipnerf-selftest" --junit "$WORK/artifacts/selftest.xml"; }
tune() {
  "$BUNDLE/mipnerf-cl" tune --minutes "$TUNE_MINUTES"
  local status=$?
  cp "$XDG_CACHE_HOME"/mipnerf-cl/*.json "$WORK/artifacts/" 2>/dev/null
  return $status
}
# bench PRESET ARGS...: one preset's bench into WORK/bench/PRESET.
bench() {
  local preset="$1"
  shift
  "$BUNDLE/mipnerf-cl" bench --presets "$preset" --out "$WORK/bench/$preset" "$@"
}
# official PRECISION: the official step in the python given, on the built-in scene (else random images).
official() {
  local scene=(--synthetic-scene "$WORK/synthetic-scene")
  if built_in_scene; then
    scene=(--data "$WORK/scene")
  fi
  "$PYTHON" "$REPO/bench/studies/official_step.py" --official "$OFFICIAL" "${scene[@]}" --precision "$1" \
    --steps "$OFFICIAL_STEPS" --batch "$PAPER_BATCH" --our-bench "$WORK/bench/paper/bench.json" \
    --out "$WORK/official/$1.json"
}
# built_in_scene: the procedural scene (one scale) in WORK/scene, made once (the official step uses it too).
built_in_scene() {
  [ -f "$WORK/scene/transforms_train.json" ] || timeout 60 "$BUNDLE/mipnerf-cl" make-scene "$WORK/scene" --scales 1 > /dev/null
}
# zipnerf: each candidate's 20 steps (one log row per step; device_check_summary.py takes the warm median).
zipnerf() {
  built_in_scene || return 1
  local status=0 candidate name settings
  for candidate in "fast:" "fast_multisampled:--set grid_multisample=true" "batch4096:--set batch_size=4096" \
      "batch4096_hash19:--set batch_size=4096 --set grid_hash_log2=19 --set grid_max=8192" \
      "batch16384_hash21:--set batch_size=16384 --set grid_hash_log2=21 --set grid_max=8192" \
      "batch4096_proposal:--set batch_size=4096 --set sampler=proposal --set grid_multisample=true"; do
    name="${candidate%%:*}"
    settings="${candidate#*:}"
    # shellcheck disable=SC2086  # the settings are words
    "$BUNDLE/mipnerf-cl" train --model zipnerf --data "$WORK/scene" --out "$WORK/zipnerf/$name" --steps 20 \
      --set log_every=1 --set val_views=1 --set checkpoint_every=1000 $settings || status=1
  done
  return $status
}
train() { "$BUNDLE/mipnerf-cl" train --preset quick --steps "$TRAIN_STEPS" --out "$WORK/train"; }
render() {
  "$BUNDLE/mipnerf-cl" render --checkpoint "$WORK/train" --path orbit --frames 24 --size "$RENDER_SIZE" \
    --out "$WORK/train/render_orbit"
}

# python: in this shell, so that the PYTHONPATH of the carried wheels reaches the official steps.
python_step() {
  local t0 t1 status=ok note=""
  t0=$(date +%s.%N)
  printf '\n===== python (%s)\n' "$python" >> "$log"
  if ! timeout 60 "$python" -c 'import gin' >> "$log" 2>&1; then
    if ls "$wheels"/*.whl > /dev/null 2>&1 &&
        timeout 60 "$python" -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --target "$work/site" \
          "$wheels"/*.whl >> "$log" 2>&1; then
      export PYTHONPATH="$work/site${PYTHONPATH:+:$PYTHONPATH}"
      note="gin-config installed from $wheels; "
    else
      status=failed; note="the python has no gin and no wheel of it installed from $wheels; "
    fi
  fi
  local versions
  versions="$(timeout 90 "$python" -c '
import sys, jax, flax, optax, numpy
print(f"python {sys.version.split()[0]}, jax {jax.__version__}, flax {flax.__version__}, optax {optax.__version__}, "
      f"numpy {numpy.__version__}; devices {jax.devices()}")' 2>> "$log")" || { status=failed; versions="JAX did not import or start (log)"; }
  echo "$versions" >> "$log"
  fact python "$versions"
  t1=$(date +%s.%N)
  record python "$status" - "$(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.1f", b - a }')" - "$note$versions"
}

summarise() {
  python3 "$repo/scripts/device_check_summary.py" --work "$work" --out "$out" --budget "$(scaled "$budget")" \
    --seconds "$(( $(date +%s) - started ))" >> "$log" 2>&1 ||
    { echo "device-check: the summary could not be written (log.txt); the steps:"; cat "$work/steps.tsv"; } |
    tee "$out/summary.md"
  # Everything else small enough to bring back, in one file: bench.md files, the self-test's JUnit file, the tuning
  # file, the training run without its checkpoints, the orbit's frames.
  (cd "$work" && tar --exclude='*.mnck' --exclude='train/scene' -czf "$out/artifacts.tar.gz" artifacts bench \
    $(ls -d train official zipnerf 2>/dev/null) steps.tsv facts.tsv) >> "$log" 2>&1
  rm -rf "$work"
}

fact bundle "$(sed -n 's/^sources: *//p' "$bundle/MANIFEST.txt" 2>/dev/null | head -n 1) ($(sed -n 's/^size: *//p' "$bundle/MANIFEST.txt" 2>/dev/null))"
fact command "scripts/device-check.sh $arguments"
say "bundle $bundle, official code $official, results in $out, budget $(scaled "$budget") s"
if [ ! -x "$bundle/mipnerf-cl" ]; then
  opencl_problem="no bundle at $bundle (scripts/prepare-device-check.sh makes one)"
  say "$opencl_problem"
fi

wanted driver && driver_step
run_step devices 30 $((deadline - reserve)) devices || opencl_problem="${opencl_problem:-mipnerf-cl devices failed (log.txt)}"
run_step selftest 90 $((deadline - reserve)) selftest
run_step tune $((tune_minutes * 60 + 45)) $((deadline - reserve)) tune
run_step bench-quick 60 $((deadline - reserve)) bench quick --sections gemm,kernels,train --time-box 30 \
  --gemm-rows "$gemm_rows"
run_step bench-small 40 $((deadline - reserve)) bench small --sections train --time-box 20
run_step bench-paper 60 $((deadline - reserve)) bench paper --sections train --time-box 30 --paper-steps 5 \
  --set "batch_size=$paper_batch"
run_step zipnerf 60 $((deadline - reserve)) zipnerf
if [ ! -d "$official/internal" ]; then
  for name in python official-default official-float32; do
    record "$name" skipped - 0 - "no official code at $official (scripts/prepare-device-check.sh copies it)"
  done
else
  wanted python && python_step
  run_step official-default 100 "$deadline" official default
  run_step official-float32 80 "$deadline" official float32
fi
run_step train 60 "$deadline" train
run_step render 30 "$deadline" render
summarise
cat "$out/summary.md"
