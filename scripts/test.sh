#!/usr/bin/env bash
# The test command of the README and of CI: install dependencies, build, then run every test stage and end with a
# table of what each stage ran, where, and how it went:
#   pocl       the whole suite on PoCL's CPU device (but the stages below)
#   mpi        the MPI tests (mpirun -np 2) on PoCL
#   oclgrind   the kernel tests under the oclgrind simulator
#   sanitizer  the suite built with clang++ under AddressSanitizer + UBSan, on PoCL (scripts/test-sanitize.sh), but
#              the `quality` tests and the `sweep` tests (a training step against the double reference for variant
#              after variant: their time under ASan is the reference's; tests/CMakeLists.txt says what runs their host
#              code there) and the reliability tests (SIGKILL at random moments, disk full: process orchestration around
#              the checkpoint code, which the train tests and the checkpoint fuzz target run under the sanitizers; 82 s
#              there; left out 2026-12-02 to keep the command under 45 minutes)
#   fuzz       each fuzz target for 12 s, in that build, each with at least 1,000 inputs run
#   tsan       the tests whose code starts threads (label `threads`: the viewer, its server, the scene writers, the host
#              MLP's threads in training) built with clang++ under ThreadSanitizer (scripts/test-tsan.sh), on PoCL
#   intel      the suite on Intel's CPU OpenCL runtime, a second, independent implementation (from PyPI), but the
#              `quality` tests and the tests of what does not depend on the OpenCL runtime: the CLI's (arguments,
#              files, messages; the device work they start is the one the library's tests run here), eval's, the
#              viewer's and the training loop's (scores, image and video files, the server and its threads; runs,
#              checkpoints, resume, budgets: their device work is the graph's steps and forward, which the graph tests
#              compare with the reference here; left out 2026-12-02 to keep the command under 45 minutes), the layering
#              check, the reliability (SIGKILL, disk-full), bench-report and MPI tests (ranks, sharding, a killed
#              rank: the process orchestration; each rank's kernels are the ones the other tests run here) and the
#              bundle test (label `bundle`: it runs PoCL through the bundle's own ICD file, whatever the stage); the
#              other stages run them
# The `quality` tests (tests/quality/: a scene trained for hundreds of steps to a PSNR) run on PoCL alone: the code
# they run is the code the train, eval and graph tests run in every stage, and their minutes there bought nothing
# the others do not show (a sanitizer report or a runtime's wrong result fails those shorter tests the same way).
#   browser    `mipnerf-cl view` in headless Chromium (scripts/test-browser.sh): a tiny run trained, its page loaded, the
#              camera dragged, the full-size frame compared with `mipnerf-cl render`, Ctrl-C; on PoCL
#   selftest   `mipnerf-selftest` on every runtime above: its --quick checks (the full list is the ops, mlp and
#              graph tests again, the same sources, which the pocl and intel stages run), and on Intel's runtime also
#              the one check only the self-test has: training steps compared with PoCL's device (--cross-device)
# Every stage runs on a platform it names and checks (MIPNERF_TEST_PLATFORM); a test that cannot run reports skipped.
# The command fails when a stage fails, runs no test, could not run or recorded nothing (scripts/stage_table.py knows
# every stage), when a test CTest did not run (a missing executable, a failed fixture), and when a test was skipped or
# a stage left out (MIPNERF_SKIP=intel,oclgrind). For local work, `--allow-skips` lets skipped tests and stages left out
# by MIPNERF_SKIP pass, and the table and its last line say so; CI=true refuses it and MIPNERF_SKIP.
# Day to day, the PoCL suite alone: ctest --test-dir build -j2 -LE '^(oclgrind|mpi)$'
set -uo pipefail
cd "$(dirname "$0")/.."
stages="pocl mpi oclgrind sanitizer fuzz tsan intel selftest browser"
ci="${CI:-false}"
allow_skips=""
for argument in "$@"; do
  case "$argument" in
    --allow-skips) allow_skips="--allow-skips" ;;
    *) echo "test: unknown argument '$argument' (the one option is --allow-skips, for local work)" >&2; exit 2 ;;
  esac
done
skip_names="${MIPNERF_SKIP:-}"
skip_list=",$skip_names,"
for name in ${skip_names//,/ }; do
  case " $stages " in *" $name "*) ;; *) echo "test: MIPNERF_SKIP names '$name', not a stage ($stages)" >&2; exit 2 ;; esac
done
if [ "$ci" = true ] && [ "$skip_list" != ",," ]; then
  echo "test: MIPNERF_SKIP='$skip_names' with CI=true: in CI every stage must run" >&2
  exit 2
fi
if [ "$ci" = true ] && [ -n "$allow_skips" ]; then
  echo "test: --allow-skips with CI=true: in CI every test must run" >&2
  exit 2
fi
./scripts/install-deps.sh --for-tests || exit 1
./scripts/build.sh || exit 1
build_dir="${BUILD_DIR:-build}"
sanitize_dir="${SANITIZE_BUILD_DIR:-build-sanitize}"
jobs="${JOBS:-$(nproc)}"
# PoCL's kernel cache of the main build's tests, for every stage on PoCL: the programs run here (the self-test, the
# browser's `view`) and the sanitizer builds' tests (scripts/test-sanitize.sh, test-tsan.sh) are served the kernels the
# `pocl` stage compiled, the same sources with the same options, instead of compiling them again.
export POCL_CACHE_DIR="$(cd "$build_dir" && pwd)/pocl-cache"
results="$(mktemp -d)"
trap 'rm -rf "$results"' EXIT
start_all=$(date +%s)
pocl_platform="Portable Computing Language"
oclgrind_platform="Oclgrind"

# wanted NAME: whether the stage is to run (MIPNERF_SKIP does not name it).
wanted() { case "$skip_list" in *",$1,"*) return 1 ;; esac; }

# record STAGE WHERE JUNIT NOTE SECONDS: one row of the closing table (JUNIT: the stage's results, or "").
record() { printf '%s\t%s\t%s\t%s\t%s\n' "$1" "$2" "$3" "$4" "${5:-0}" >> "$results/rows.tsv"; }

# device_of SELECTOR: the name of the device the executable picks for SELECTOR, run under $DEVICE_LAUNCHER when set
# (oclgrind: its platform exists only inside its launcher, as the stage's tests run).
device_of() {
  ${DEVICE_LAUNCHER:-} "$build_dir/mipnerf-cl" --device "$1" devices 2>/dev/null |
    sed -n 's/^\[[0-9]*\] \(.*\)   <- selected.*/\1/p'
}

# run_ctest STAGE PLATFORM BUILD_DIR CTEST_ARGS...: a stage of CTest tests, the tests and the executable both on
# PLATFORM (selected by platform, checked by MIPNERF_TEST_PLATFORM).
run_ctest() {
  local stage="$1" platform="$2" dir="$3" started
  shift 3
  started=$(date +%s)
  echo "test: stage '$stage' on platform '$platform' ($(device_of "platform=$platform"))"
  MIPNERF_TEST_PLATFORM="$platform" MIPNERF_TEST_DEVICE="platform=$platform" MIPNERF_DEVICE="platform=$platform" \
    ctest --test-dir "$dir" --output-on-failure -j "$jobs" --output-junit "$results/$stage.xml" "$@"
  record "$stage" "$platform: $(device_of "platform=$platform")" "$results/$stage.xml" "" $(( $(date +%s) - started ))
}

# run_selftest PLATFORM full|quick|quick-cross [LAUNCHER...]: mipnerf-selftest on that platform, all its checks, --quick,
# or --quick --cross-device.
run_selftest() {
  local platform="$1" mode="$2" started quick=()
  shift 2
  [ "$mode" = quick ] && quick=(--quick)
  [ "$mode" = quick-cross ] && quick=(--quick --cross-device)
  started=$(date +%s)
  echo "test: stage 'selftest' on platform '$platform'"
  "$@" "$build_dir/mipnerf-selftest" "${quick[@]}" --device "platform=$platform" --expect-platform "$platform" \
    --junit "$results/selftest-$platform.xml"
  record selftest "$platform" "$results/selftest-$platform.xml" "exit $?" $(( $(date +%s) - started ))
}

for name in ${skip_names//,/ }; do record "$name" "-" "" "left out by request (MIPNERF_SKIP)"; done

# PoCL: the suite, then the MPI tests, and the self-test.
if wanted pocl; then run_ctest pocl "$pocl_platform" "$build_dir" -LE '^(oclgrind|mpi)$'; fi
if wanted mpi; then run_ctest mpi "$pocl_platform" "$build_dir" -L '^mpi$'; fi
if wanted selftest; then run_selftest "$pocl_platform" quick; fi

# The browser: `view` on a tiny run in headless Chromium, with selenium from PyPI (a venv in the cache folder). Exit 77
# means Chromium, its driver or selenium is missing here, which the test command's packages should have installed:
# the stage could not run.
if wanted browser; then
  started=$(date +%s)
  echo "test: stage 'browser' on platform '$pocl_platform'"
  MIPNERF_DEVICE="platform=$pocl_platform" BUILD_DIR="$build_dir" ./scripts/test-browser.sh --junit "$results/browser.xml"
  status=$?
  if [ $status -eq 77 ]; then
    record browser "-" "" "could not run: chromium, chromium-driver or selenium is missing (above)"
  else
    record browser "$pocl_platform: $(device_of "platform=$pocl_platform")" "$results/browser.xml" "exit $status" \
      $(( $(date +%s) - started ))
  fi
fi

# oclgrind: the kernel tests under the simulator, and the self-test under it.
if wanted oclgrind; then
  if command -v oclgrind >/dev/null; then
    DEVICE_LAUNCHER=oclgrind run_ctest oclgrind "$oclgrind_platform" "$build_dir" -L '^oclgrind$'
    if wanted selftest; then run_selftest "$oclgrind_platform" quick oclgrind; fi
  else
    record oclgrind "-" "" "could not run: oclgrind is not installed (Debian package 'oclgrind')"
  fi
fi

# The sanitizer build (clang++, ASan + UBSan, no MPI): its suite but the oclgrind and MPI tests (run above), then
# the fuzz targets' short runs.
if wanted sanitizer || wanted fuzz; then
  if ./scripts/test-sanitize.sh --build-only; then
    if wanted sanitizer; then run_ctest sanitizer "$pocl_platform" "$sanitize_dir" -LE '^(oclgrind|fuzz|mpi|quality|sweep|reliability)$'; fi
    if wanted fuzz; then run_ctest fuzz "$pocl_platform" "$sanitize_dir" -L '^fuzz$'; fi
  else
    for stage in sanitizer fuzz; do
      if wanted "$stage"; then record "$stage" "-" "" "could not run: the sanitizer build failed (above)"; fi
    done
  fi
fi

# The thread-sanitizer build (clang++, TSan, no MPI): the tests labelled `threads` and the fixtures they need.
if wanted tsan; then
  tsan_dir="${TSAN_BUILD_DIR:-build-tsan}"
  if ./scripts/test-tsan.sh --build-only; then
    run_ctest tsan "$pocl_platform" "$tsan_dir" -L '^threads$'
  else
    record tsan "-" "" "could not run: the thread-sanitizer build failed (above)"
  fi
fi

# Intel's CPU OpenCL runtime, installed into a cache folder from PyPI; its platform name comes from the runtime.
if wanted intel; then
  if environment="$(./scripts/install-intel-opencl.sh)"; then
    eval "$environment"
    run_ctest intel "$INTEL_OPENCL_PLATFORM" "$build_dir" -LE '^(oclgrind|quality|reliability|bench|mpi|bundle)$' \
      -E '^((cli|layers): |(eval|view|train):)'
    if wanted selftest; then run_selftest "$INTEL_OPENCL_PLATFORM" quick-cross; fi
  else
    record intel "-" "" "could not run: Intel's CPU runtime could not be installed (above)"
  fi
fi

# The closing table, and the command's status.
python3 scripts/stage_table.py "$results/rows.tsv" $allow_skips --seconds $(( $(date +%s) - start_all ))
