#!/usr/bin/env bash
# The bundle test (tests/bundle/bundle_tests.cmake): packs BUILD_DIR with scripts/bundle.sh into a temporary folder
# outside the build, with the bundle's own ICD file for this machine's PoCL, then checks that
#   - every library the packed executables load (but glibc's) is the bundle's copy, with nothing else on the path;
#   - each executable starts through its launcher with a clean environment (env -i: only PATH, HOME, the ICD folder
#     and PoCL's kernel cache), from a folder outside the build;
#   - `devices` lists PoCL through the bundle's vendors/ folder, and lists nothing with an empty vendors folder (so
#     the host's /etc/OpenCL/vendors is not what it read);
#   - a tiny `train` runs to its val score, with the bundle's libstdc++ forced too (MIPNERF_BUNDLE_COMPAT=1).
# Usage: test_bundle.sh BUILD_DIR
set -uo pipefail
build_dir="$(cd "${1:?usage: test_bundle.sh BUILD_DIR}" && pwd)"
source_dir="$(cd "$(dirname "$0")/../.." && pwd)"
work="$(mktemp -d "${TMPDIR:-/tmp}/mipnerf-bundle-test.XXXXXX")"
trap 'rm -rf "$work"' EXIT
bundle="$work/bundle"
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }

# clean_run [VAR=value...] -- PROGRAM ARGS: the program with only PATH, HOME, the bundle's ICD folder and PoCL's cache
# (the build's, which the other tests fill: kernels compile once) in its environment, from $work/elsewhere.
clean_run() {
  local extra=()
  while [ "$1" != "--" ]; do extra+=("$1"); shift; done
  shift
  (cd "$work/elsewhere" && env -i PATH=/usr/bin:/bin:/usr/sbin:/sbin HOME="$work/home" \
    OCL_ICD_VENDORS="$bundle/vendors" POCL_CACHE_DIR="${POCL_CACHE_DIR:-$work/pocl-cache}" "${extra[@]}" "$@")
}

if ! "$source_dir/scripts/bundle.sh" --from-build "$build_dir" --pocl-icd --max-mib 0 "$bundle"; then
  echo "FAIL: scripts/bundle.sh --from-build $build_dir failed (above)"
  exit 1
fi
mkdir -p "$work/elsewhere" "$work/home" "$work/empty-vendors"
echo "bundle: $(du -sh "$bundle" | cut -f1), vendors/pocl.icd -> $(cat "$bundle/vendors/pocl.icd")"

# Every library resolved inside the bundle, but glibc's (an independent reading of what bundle.sh checks itself).
for exe in "$bundle"/bin/*; do
  outside="$(env -i LD_LIBRARY_PATH="$bundle/lib:$bundle/lib/compat" ldd "$exe" | awk -v b="$bundle/" '
    / => / && $3 !~ "^" b && $1 !~ /^(libc|libm|libdl|libpthread|librt|libresolv)\.so\.|^ld-linux/ {print $1 " " $3}')"
  [ -z "$outside" ] || fail "$(basename "$exe") loads libraries from outside the bundle: $outside"
  [ -x "$bundle/$(basename "$exe")" ] || fail "no launcher $bundle/$(basename "$exe")"
done

# Each test executable starts (its libraries load) and knows its test cases.
for exe in "$bundle"/bin/test_*; do
  name="$(basename "$exe")"
  count="$(clean_run -- "$bundle/$name" --count 2>&1 | sed -n 's/.*passing the current filters: \([0-9]*\).*/\1/p')"
  [ "${count:-0}" -gt 0 ] || fail "$name --count through the launcher gave no test cases"
done
clean_run -- "$bundle/mipnerf-selftest" --help > /dev/null 2>&1 || fail "mipnerf-selftest --help did not run"

# devices: PoCL through the bundle's ICD file, and nothing through an empty folder.
listing="$(clean_run -- "$bundle/mipnerf-cl" devices 2>&1)"
echo "$listing" | head -3
echo "$listing" | grep -q "platform *Portable Computing Language" || fail "devices did not list PoCL: $listing"
echo "$listing" | grep -q "<- selected" || fail "devices selected no device"
empty="$(clean_run OCL_ICD_VENDORS="$work/empty-vendors" -- "$bundle/mipnerf-cl" devices 2>&1)"
if [ $? -eq 0 ] || ! echo "$empty" | grep -q "no OpenCL platform"; then
  fail "devices with an empty OCL_ICD_VENDORS folder did not fail with 'no OpenCL platform' (the host's vendors were read?): $empty"
fi

# A tiny training run, with the bundle's own libstdc++ on the path.
train_log="$(clean_run MIPNERF_BUNDLE_COMPAT=1 -- "$bundle/mipnerf-cl" --device "platform=Portable Computing Language" \
  train --preset tiny --steps 4 --val-views 1 --out "$work/elsewhere/run" 2>&1)"
status=$?
echo "$train_log" | tail -2
[ $status -eq 0 ] || fail "train exited with $status: $(echo "$train_log" | tail -5)"
echo "$train_log" | grep -q "val PSNR [0-9.]* dB" || fail "train printed no val PSNR"
ls "$work/elsewhere/run/checkpoints/"*.mnck > /dev/null 2>&1 || fail "train wrote no checkpoint"

if [ $failures -gt 0 ]; then
  echo "bundle test: $failures check(s) failed"
  exit 1
fi
echo "bundle test: passed"
