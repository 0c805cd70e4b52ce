#!/usr/bin/env bash
# Packs mipnerf-cl, mipnerf-selftest and the GPU suite's test executables (ops, mlp, graph, official) with every shared
# library they load beyond glibc into one folder that runs on another x86-64 Linux with glibc at least as new as this
# one (Debian 12: 2.36; Ubuntu 24.04 has 2.39), e.g. the device machine lent to a session (docs/devices.md):
#
#   scripts/bundle.sh OUT                      build the bundle configuration in build-bundle/, then pack it into OUT
#   scripts/bundle.sh --from-build DIR OUT     pack an existing build as it is (no configure, no build)
#
# The bundle configuration leaves out what a GPU run never loads but costs most of the size: FFmpeg (render --video),
# PLplot (plot), MPI, and the host BLAS libraries (OpenBLAS, BLIS, oneDNN, libxsmm: they run the MLP only on CPU
# devices; without them CLBlast runs it there too, as on a GPU). The full build's libraries are about 263 MB (67 MB
# even as .tar.xz), over the 64 MiB a device call may carry.
#
# OUT holds bin/ (the executables, stripped), lib/ (their libraries, by soname), lib/compat/ (libstdc++ and libgcc_s,
# put on the library path only where the system's are older than the build's), vendors/ (OpenCL ICD files: empty
# unless --pocl-icd), one launcher per executable (OUT/mipnerf-cl ..., all through OUT/run, which sets
# LD_LIBRARY_PATH) and MANIFEST.txt (sources, versions, sizes). OpenCL drivers are not packed: the ICD loader finds
# them through OCL_ICD_VENDORS (a folder of .icd files), else /etc/OpenCL/vendors. Kernels are embedded in the
# executables.
#
# Options:
#   --from-build DIR   pack this build instead of building build-bundle/ (BUILD_DIR overrides that folder's name)
#   --pocl-icd         write OUT/vendors/pocl.icd naming this machine's PoCL library (rehearsals and the bundle
#                      test; not for a GPU machine, which has no PoCL)
#   --max-mib N        fail when the bundle is larger than N MiB (default 48; 0: no limit)
set -euo pipefail
cd "$(dirname "$0")/.."
source_dir="$PWD"
usage() { sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//' >&2; exit 2; }

from_build=""
pocl_icd=false
max_mib=48
out=""
while [ $# -gt 0 ]; do
  case "$1" in
    --from-build) from_build="${2:?--from-build needs a build folder}"; shift 2 ;;
    --pocl-icd) pocl_icd=true; shift ;;
    --max-mib) max_mib="${2:?--max-mib needs a number}"; shift 2 ;;
    -h|--help) usage ;;
    -*) echo "bundle: unknown option '$1' (--from-build DIR, --pocl-icd, --max-mib N)" >&2; exit 2 ;;
    *) [ -z "$out" ] || { echo "bundle: one output folder, got '$out' and '$1'" >&2; exit 2; }; out="$1"; shift ;;
  esac
done
[ -n "$out" ] || { echo "bundle: name the output folder: scripts/bundle.sh [options] OUT" >&2; exit 2; }

# The executables packed: the CLI, the self-test, and the test areas whose kernels a GPU run checks (their doctest
# executables run without CTest: test_ops -tc='...'; test_official reads tests/official/fixtures, found through
# MIPNERF_OFFICIAL_FIXTURES).
executables=(mipnerf-cl mipnerf-selftest tests/test_ops tests/test_gemm tests/test_mlp tests/test_graph tests/test_official)
targets=(mipnerf-cl mipnerf-selftest test_ops test_gemm test_mlp test_graph test_official)

# glibc's own libraries and the dynamic loader: every Linux has them, and a copy of them must never be loaded.
is_glibc() { [[ "$1" =~ ^(libc|libm|libdl|libpthread|librt|libresolv|libutil|libanl|libmvec|libnsl|libBrokenLocale|libthread_db)\.so\. || "$1" =~ ^ld-linux || "$1" =~ ^linux-vdso ]]; }
# Libraries every system with a C++ program has, newer than ours on the targets we know: packed in lib/compat/ and put
# on the path only where the system's copy is older (its newer copy may be needed by a driver loaded into the process).
is_compat() { [[ "$1" =~ ^(libstdc\+\+\.so\.6|libgcc_s\.so\.1)$ ]]; }

if [ -z "$from_build" ]; then
  build_dir="${BUILD_DIR:-build-bundle}"
  jobs="${JOBS:-$(nproc)}"
  export CMAKE_CXX_COMPILER_LAUNCHER="${CMAKE_CXX_COMPILER_LAUNCHER:-$(command -v ccache || true)}"
  export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$PWD}"
  # OFF as a library's value keeps find_library from searching (a cached value that is not *-NOTFOUND), and if()
  # reads it as false: the host BLAS and the CPU GEMM libraries behind it are left out.
  cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release -DMIPNERF_VIDEO=OFF -DMIPNERF_PLPLOT=OFF -DMIPNERF_MPI=OFF \
    -DMIPNERF_BUILD_BENCH=OFF -DCMAKE_DISABLE_FIND_PACKAGE_OpenBLAS=ON -DMIPNERF_CBLAS_LIBRARY=OFF >/dev/null
  cmake --build "$build_dir" -j "$jobs" --target "${targets[@]}"
else
  build_dir="$from_build"
fi
for exe in "${executables[@]}"; do
  [ -x "$build_dir/$exe" ] || { echo "bundle: $build_dir/$exe is missing: build it first (targets: ${targets[*]})" >&2; exit 1; }
done

if [ -e "$out" ]; then
  if [ -f "$out/MANIFEST.txt" ] || [ -z "$(ls -A "$out")" ]; then
    rm -rf "$out"
  else
    echo "bundle: $out exists and is not a bundle (no MANIFEST.txt): not overwriting it" >&2
    exit 1
  fi
fi
mkdir -p "$out/bin" "$out/lib/compat" "$out/vendors"
out="$(cd "$out" && pwd)"

# The executables, without symbols or debug information.
for exe in "${executables[@]}"; do
  cp "$build_dir/$exe" "$out/bin/"
  strip --strip-all "$out/bin/$(basename "$exe")"
done

# Their libraries, as ldd resolves them here (the transitive closure), each under the name the executables ask for.
declare -A source_of=()
for exe in "$out"/bin/*; do
  while read -r name arrow path _; do
    [ "$arrow" = "=>" ] || continue
    if [ "$path" = "not" ]; then echo "bundle: $exe needs $name, which is not found here" >&2; exit 1; fi
    is_glibc "$name" && continue
    source_of["$name"]="$path"
  done < <(ldd "$exe")
done
for name in "${!source_of[@]}"; do
  destination="$out/lib"
  is_compat "$name" && destination="$out/lib/compat"
  cp -L "${source_of[$name]}" "$destination/$name"
  chmod u+w "$destination/$name"
  strip --strip-unneeded "$destination/$name" 2>/dev/null || true
done

# The newest glibc and libstdc++ symbol versions anything packed asks for: the launcher compares the system's.
symbol_versions() { objdump -T "$out"/bin/* "$out"/lib/*.so* "$out"/lib/compat/*.so* 2>/dev/null |
  grep -o "$1[0-9.]*" | sed "s/^$1//" | sort -uV | tail -1; }
glibc_needed="$(symbol_versions 'GLIBC_')"
glibcxx_needed="$(symbol_versions 'GLIBCXX_')"

if $pocl_icd; then
  pocl="$(ldconfig -p 2>/dev/null | awk '/libpocl\.so\.2 .*x86-64/ {print $NF}' | head -n 1 || true)"
  for candidate in /usr/lib/x86_64-linux-gnu/libpocl.so.2 /usr/lib64/libpocl.so.2 /usr/lib/libpocl.so.2; do
    [ -n "$pocl" ] || { [ -e "$candidate" ] && pocl="$candidate"; }
  done
  [ -n "$pocl" ] || { echo "bundle: --pocl-icd: no libpocl.so.2 here (Debian package pocl-opencl-icd)" >&2; exit 1; }
  echo "$pocl" > "$out/vendors/pocl.icd"
fi

sed -e "s/@GLIBC_NEEDED@/$glibc_needed/" -e "s/@GLIBCXX_NEEDED@/$glibcxx_needed/" \
  "$source_dir/scripts/bundle_launcher.sh" > "$out/run"
chmod +x "$out/run"
for exe in "$out"/bin/*; do
  name="$(basename "$exe")"
  printf '#!/bin/sh\n# %s of this bundle, through ./run (the bundle'\''s libraries first on the library path).\nexec "$(dirname "$0")/run" %s "$@"\n' \
    "$name" "$name" > "$out/$name"
  chmod +x "$out/$name"
done

# Every library an executable loads through the launcher's path must be the bundle's, but glibc's.
verify_closure() {
  local exe line
  for exe in "$out"/bin/*; do
    while read -r line; do
      set -- $line
      [ "${2:-}" = "=>" ] || continue
      is_glibc "$1" && continue
      case "$3" in "$out"/lib/*) ;; *) echo "bundle: $(basename "$exe") loads $1 from $3, outside the bundle" >&2; return 1 ;; esac
    done < <(env -i PATH="$PATH" LD_LIBRARY_PATH="$out/lib:$out/lib/compat" ldd "$exe")
  done
}
verify_closure

bytes="$(du -sb "$out" | cut -f1)"
mib="$(awk -v b="$bytes" 'BEGIN { printf "%.1f", b / 1048576 }')"
{
  echo "mipnerf-cl bundle: run ./mipnerf-cl, ./mipnerf-selftest or ./test_<area> here; OCL_ICD_VENDORS names a folder"
  echo "of OpenCL .icd files (else /etc/OpenCL/vendors is read). See docs/devices.md of the sources."
  echo
  echo "made:       $(date -u +%Y-%m-%dT%H:%M:%SZ) on $(uname -n) ($(. /etc/os-release && echo "$PRETTY_NAME"), $(getconf GNU_LIBC_VERSION))"
  echo "sources:    $(git -C "$source_dir" rev-parse HEAD 2>/dev/null || echo unknown)$(git -C "$source_dir" diff --quiet HEAD 2>/dev/null || echo ' (with uncommitted changes)')"
  echo "build:      $build_dir ($(grep -E '^MIPNERF_(VIDEO|PLPLOT|MPI):' "$build_dir/CMakeCache.txt" | tr '\n' ' '))"
  echo "needs:      x86-64 Linux, glibc >= $glibc_needed; libstdc++ with GLIBCXX_$glibcxx_needed (else lib/compat's)"
  echo "size:       $bytes bytes ($mib MiB)"
  echo
  echo "executables (stripped; sha256):"
  (cd "$out/bin" && sha256sum -- * | sed 's/^/  /')
  echo
  echo "libraries (bytes, packed from):"
  for name in $(printf '%s\n' "${!source_of[@]}" | sort); do
    file="$out/lib/$name"; is_compat "$name" && file="$out/lib/compat/$name"
    printf '  %-34s %10d  %s\n' "$name" "$(stat -c %s "$file")" "$(readlink -f "${source_of[$name]}")"
  done
  echo
  echo "vendors/: $(ls "$out/vendors" | tr '\n' ' ')"
} > "$out/MANIFEST.txt"

echo "bundle: $out: ${#executables[@]} executables, ${#source_of[@]} libraries, $mib MiB (glibc >= $glibc_needed)"
if [ "$max_mib" != 0 ] && [ "$bytes" -gt $((max_mib * 1048576)) ]; then
  echo "bundle: $mib MiB is over the limit of $max_mib MiB (--max-mib); the largest files:" >&2
  find "$out" -type f -printf '%s %P\n' | sort -rn | head -8 | sed 's/^/  /' >&2
  exit 1
fi
