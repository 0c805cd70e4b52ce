#!/usr/bin/env bash
# The long fuzzing runs: every fuzz target (tests/fuzz, one per reader of outside data) for RUNS executions from a
# copy of its committed seed corpus, under AddressSanitizer + UBSan, two targets at a time at most; writes
# bench/results/fuzz/fuzz.md (executions, coverage, corpus, wall time, crashes per target; machine, clang, date).
#
#   scripts/fuzz.sh [--runs N] [--jobs J] [--report-only] [TARGET ...]   (default: 1000000 runs, 2 jobs, every target)
#
# --report-only writes the report again from the last runs' logs without fuzzing (their --runs and --jobs must be
# given again, as the report states them).
#
# Builds the sanitizer + fuzz build folder first (${SANITIZE_BUILD_DIR:-build-sanitize}, clang++; see
# scripts/test-sanitize.sh). Each run's corpus, log and any crash input stay in BUILD/fuzz-runs/<target>/; the
# committed corpus is not modified. A crash stops that target's run, is listed, and makes the script exit 1: reproduce
# with `BUILD/tests/fuzz_<target> CRASH_FILE`, fix the reader, and commit the input as
# tests/fuzz/corpus/<target>/regress-<what it was> (the CTest entries then replay it on every run).
set -euo pipefail
cd "$(dirname "$0")/.."
runs=1000000
jobs=2
report_only=0
targets=()
while [ $# -gt 0 ]; do
  case "$1" in
    --runs) runs="$2"; shift 2 ;;
    --jobs) jobs="$2"; shift 2 ;;
    --report-only) report_only=1; shift ;;
    -h|--help) sed -n '2,16p' "$0"; exit 0 ;;
    *) targets+=("$1"); shift ;;
  esac
done
if [ ${#targets[@]} -eq 0 ]; then
  targets=(blender transforms_json multiscale llff colmap png jpeg camera_path config checkpoint view)
fi
build_dir="${SANITIZE_BUILD_DIR:-build-sanitize}"
root="$PWD"

if [ "$report_only" = 0 ]; then
  export CMAKE_CXX_COMPILER_LAUNCHER="${CMAKE_CXX_COMPILER_LAUNCHER:-$(command -v ccache || true)}"
  cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER=clang++ -DMIPNERF_SANITIZE=ON \
    -DMIPNERF_FUZZ=ON >/dev/null
  cmake --build "$build_dir" -j "$jobs" --target "${targets[@]/#/fuzz_}"

  # The same sanitizer settings as the CTest entries (tests/CMakeLists.txt).
  export ASAN_OPTIONS="detect_leaks=1:halt_on_error=1:intercept_tls_get_addr=0"  # see tests/CMakeLists.txt
  export LSAN_OPTIONS="suppressions=$root/tests/sanitize/lsan.supp:print_suppressions=0"
  export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"

  dictionary_for() {
    if [ -f "tests/fuzz/dictionaries/$1.dict" ]; then echo "-dict=$root/tests/fuzz/dictionaries/$1.dict"
    else
      case "$1" in  # the JSON readers without a dictionary of their own (as tests/fuzz/fuzz_tests.cmake)
        blender|transforms_json|multiscale|camera_path) echo "-dict=$root/tests/fuzz/dictionaries/json.dict" ;;
      esac
    fi
  }

  # run_target NAME: fuzzes one target; leaves log, corpus, artifacts and its wall time in BUILD/fuzz-runs/NAME.
  run_target() {
    local name="$1" work="$build_dir/fuzz-runs/$1"
    rm -rf "$work"
    mkdir -p "$work/corpus"
    cp tests/fuzz/corpus/"$name"/* "$work/corpus/"
    local start end status=0
    start=$(date +%s.%N)
    # shellcheck disable=SC2046
    "$build_dir/tests/fuzz_$name" "$work/corpus" -runs="$runs" -rss_limit_mb=2048 -malloc_limit_mb=2048 -timeout=10 \
      -max_len=65536 -print_final_stats=1 -artifact_prefix="$work/" $(dictionary_for "$name") >"$work/log" 2>&1 || status=$?
    end=$(date +%s.%N)
    echo "$status" >"$work/status"
    echo "$start $end" | awk '{printf "%.0f\n", $2 - $1}' >"$work/seconds"
    echo "fuzz: $name: exit $status after $(cat "$work/seconds") s"
  }

  echo "fuzz: ${targets[*]}: $runs runs each, $jobs at a time (logs in $build_dir/fuzz-runs)"
  git rev-parse --short HEAD >"$build_dir/fuzz-runs/commit" 2>/dev/null || echo "?" >"$build_dir/fuzz-runs/commit"
  overall_start=$(date +%s)
  running=0
  for name in "${targets[@]}"; do
    if [ "$running" -ge "$jobs" ]; then
      wait -n
      running=$((running - 1))
    fi
    run_target "$name" &
    running=$((running + 1))
  done
  wait
  overall_seconds=$(( $(date +%s) - overall_start ))
  echo "$overall_seconds" >"$build_dir/fuzz-runs/total_seconds"
  date -u +%Y-%m-%dT%H:%M:%SZ >"$build_dir/fuzz-runs/finished"
fi
overall_seconds=$(cat "$build_dir/fuzz-runs/total_seconds" 2>/dev/null || echo "?")
finished=$(cat "$build_dir/fuzz-runs/finished" 2>/dev/null || echo "?")
commit=$(cat "$build_dir/fuzz-runs/commit" 2>/dev/null || echo "?")

# The report.
out=bench/results/fuzz/fuzz.md
cpu=$(lscpu 2>/dev/null | sed -n 's/^Model name: *//p' | head -1)
clang_version=$(clang++ --version | head -1)
failed=0
{
  echo "# Fuzzing the readers of outside data"
  echo
  echo "Runs finished: $finished (UTC), commit $commit. Command: \`scripts/fuzz.sh --runs $runs --jobs $jobs\`; ${overall_seconds} s in all."
  echo
  echo "Host: ${cpu:-unknown CPU}, $(nproc) hardware threads, $jobs targets at a time (shared machine). Compiler: $clang_version;"
  echo "libFuzzer with AddressSanitizer + UndefinedBehaviorSanitizer (\`-fsanitize=fuzzer,address,undefined\`), limits"
  echo "\`-rss_limit_mb=2048 -malloc_limit_mb=2048 -timeout=10\`. Each target starts from its committed seed corpus"
  echo "(tests/fuzz/corpus/<target>: test fixtures and every input that once crashed a reader, \`regress-*\`)."
  echo
  echo "A target passes when every input either reads or throws \`mipnerf::Error\` with one line naming the file"
  echo "(tests/fuzz/fuzz_support.hpp); any other exception, sanitizer report, hang or allocation over the limit is a crash."
  echo "Coverage is libFuzzer's at the end of the run: \`cov\` = covered edges of the instrumented code (host/core, io,"
  echo "data, the training settings, the target), \`ft\` = features (edges with hit counts, comparisons)."
  echo
  echo "| target | executions | cov | ft | corpus (inputs / bytes) | wall s | exec/s | crashes this run | regression inputs (crashes found and fixed) |"
  echo "|---|---:|---:|---:|---:|---:|---:|---:|---|"
  for name in "${targets[@]}"; do
    work="$build_dir/fuzz-runs/$name"
    log="$work/log"
    executions=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
    last=$(grep -E '^#[0-9]+' "$log" | tail -1 || true)
    cov=$(echo "$last" | sed -n 's/.* cov: \([0-9]*\).*/\1/p')
    ft=$(echo "$last" | sed -n 's/.* ft: \([0-9]*\).*/\1/p')
    corpus_files=$(find "$work/corpus" -type f | wc -l)
    corpus_bytes=$(du -sb "$work/corpus" | cut -f1)
    seconds=$(cat "$work/seconds")
    rate=$(awk -v e="${executions:-0}" -v s="$seconds" 'BEGIN { printf "%.0f", (s > 0 ? e / s : 0) }')
    crashes=$(find "$work" -maxdepth 1 -type f \( -name 'crash-*' -o -name 'leak-*' -o -name 'timeout-*' -o -name 'oom-*' \) | wc -l)
    status=$(cat "$work/status")
    if [ "$status" != 0 ] && [ "$crashes" = 0 ]; then crashes="exit $status"; fi
    if [ "$crashes" != 0 ]; then failed=1; fi
    regressions=$(find "tests/fuzz/corpus/$name" -name 'regress-*' -printf '%f\n' | sort | sed 's/^regress-//' | paste -sd, - | sed 's/,/, /g')
    count=$(find "tests/fuzz/corpus/$name" -name 'regress-*' | wc -l)
    echo "| $name | ${executions:-?} | ${cov:-?} | ${ft:-?} | $corpus_files / $corpus_bytes | $seconds | $rate | $crashes | $count${regressions:+: $regressions} |"
  done
} >"$out"
echo "fuzz: wrote $out"
if [ "$failed" != 0 ]; then
  echo "fuzz: a target crashed: its input is in $build_dir/fuzz-runs/<target>/ (see the table)" >&2
  exit 1
fi
