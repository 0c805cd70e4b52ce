#!/usr/bin/env bash
# Installs Intel's CPU OpenCL runtime (PyPI: intel-opencl-rt and its compiler runtime intel-cmplr-lib-rt) into a
# cache folder, as a second, independent OpenCL implementation to run the suite on, and writes an ICD vendors folder
# that lists it beside the system's ICDs (PoCL). Prints the environment that makes programs see it, one `export`
# per line, for `eval "$(scripts/install-intel-opencl.sh)"`; everything else goes to stderr.
#
# Why a vendors folder and not LD_LIBRARY_PATH: the wheel ships its own libOpenCL.so, which would shadow the system
# ICD loader if its lib/ were on the library path. libintelocl.so finds its private libraries (libsvml, libimf,
# libirng, libintlc, TBB) through its RUNPATH ($ORIGIN), so the ICD file naming its absolute path is enough.
#
# Exits 1 with one line on stderr when the runtime cannot be installed (no network, no python3-venv, ...).
set -euo pipefail

cache="${MIPNERF_CACHE_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/mipnerf-cl}/intel-opencl"
version="${INTEL_OPENCL_VERSION:-2026.2.0}"
venv="$cache/venv-$version"
vendors="$cache/vendors"
python="$(command -v /usr/bin/python3 || command -v python3 || true)"

fail() { echo "install-intel-opencl: $*" >&2; exit 1; }

[ -n "$python" ] || fail "no python3 to install the runtime with (scripts/install-deps.sh installs it)"
if [ ! -e "$venv/lib/libintelocl.so" ]; then
  echo "install-intel-opencl: installing intel-opencl-rt $version into $venv (about 700 MB)" >&2
  "$python" -m venv "$venv" >&2 || fail "python3 -m venv failed (Debian: apt-get install python3-venv)"
  "$venv/bin/pip" install --quiet --disable-pip-version-check "intel-opencl-rt==$version" \
    "intel-cmplr-lib-rt==$version" >&2 || fail "pip could not install intel-opencl-rt==$version (network?)"
fi
library="$venv/lib/libintelocl.so"
[ -e "$library" ] || fail "$library is missing after the install"
missing="$(ldd "$library" | grep 'not found' | sort -u | tr -s ' \t\n' ' ' || true)"
[ -z "$missing" ] || fail "$library cannot load: $missing"

# The vendors folder: the system's ICD files and Intel's, with an absolute path (the wheel's own .icd file names a
# build machine's path).
rm -rf "$vendors"
mkdir -p "$vendors"
for icd in /etc/OpenCL/vendors/*.icd; do
  [ -e "$icd" ] && cp "$icd" "$vendors/"
done
echo "$library" > "$vendors/intel-cpu.icd"

# The runtime's own platform name, asked of it alone (a folder listing only its ICD file).
alone="$cache/vendors-intel-only"
rm -rf "$alone"
mkdir -p "$alone"
echo "$library" > "$alone/intel-cpu.icd"
command -v clinfo >/dev/null || fail "clinfo is missing (scripts/install-deps.sh installs it)"
platform="$(OCL_ICD_VENDORS="$alone" clinfo -l 2>/dev/null | sed -n 's/^Platform #0: //p')"
[ -n "$platform" ] || fail "$library is installed but lists no OpenCL platform (clinfo -l over it alone)"

echo "export OCL_ICD_VENDORS=$vendors"
printf 'export INTEL_OPENCL_PLATFORM=%q\n' "$platform"
