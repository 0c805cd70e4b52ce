#!/usr/bin/env bash
# The browser stage: `mipnerf-cl view` in Debian's headless Chromium (tests/browser/test_viewer.py), driven by
# selenium from PyPI, installed into a cache folder's virtual environment on first use (as Intel's runtime is).
#   scripts/test-browser.sh [--junit FILE] [--screenshot FILE.png]      (BUILD_DIR: the build, default build)
# Exit status: the test's (0 passed, 1 failed, 77 could not run here), or 1 when selenium cannot be installed.
set -euo pipefail
cd "$(dirname "$0")/.."
build_dir="${BUILD_DIR:-build}"
cache="${MIPNERF_CACHE_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/mipnerf-cl}/browser"
version="${SELENIUM_VERSION:-4.27.1}"
venv="$cache/venv-selenium-$version"
python="$(command -v /usr/bin/python3 || command -v python3)"
if [ ! -x "$venv/bin/python" ] || ! "$venv/bin/python" -c "import selenium" 2>/dev/null; then
  echo "test-browser: installing selenium $version into $venv" >&2
  "$python" -m venv "$venv" >&2 || { echo "test-browser: python3 -m venv failed (Debian: python3-venv)" >&2; exit 1; }
  "$venv/bin/pip" install --quiet --disable-pip-version-check "selenium==$version" >&2 ||
    { echo "test-browser: pip could not install selenium==$version (network?)" >&2; exit 1; }
fi
work="$(mktemp -d "${TMPDIR:-/tmp}/mipnerf-browser-XXXXXX")"
trap 'rm -rf "$work"' EXIT
status=0
"$venv/bin/python" tests/browser/test_viewer.py --exe "$build_dir/mipnerf-cl" --work "$work/test" "$@" || status=$?
exit $status
