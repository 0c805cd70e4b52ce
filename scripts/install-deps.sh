#!/usr/bin/env bash
# Installs the Debian packages mipnerf-cl needs: to build and run it (the quick start); with --with-colmap also COLMAP,
# which `dataset from-photos` runs (a large package: Qt and Ceres come with it, so the quick start leaves it out); with
# --for-tests also what the test command's stages need (oclgrind, clang with its sanitizer runtimes, Open MPI, COLMAP,
# Chromium), plus any package named as an argument (bench/setup.sh adds what the studies need:
# scripts/install-deps.sh python3-matplotlib).
# Idempotent and non-interactive: packages already installed are skipped; uses sudo when not root.
set -euo pipefail

# What the quick start needs: to configure and link the executable (the optional libraries below are linked when
# found, so each is kept), to run it on PoCL, and python3 for scripts/time_to_output.py.
packages=(
  build-essential cmake pkg-config python3
  ocl-icd-opencl-dev opencl-c-headers opencl-clhpp-headers pocl-opencl-icd
  libclblast-dev libopenexr-dev libcli11-dev doctest-dev
  nlohmann-json3-dev libpng-dev libjpeg-dev zlib1g-dev
  libplplot-dev plplot-driver-cairo  # `mipnerf-cl plot`: curves as SVG, and as PNG through PLplot's cairo driver
  libavformat-dev libavcodec-dev libswscale-dev libavutil-dev  # `render --video`: H.264 MP4 (Debian's libx264 encoder)
  libopenblas-dev   # the host GEMM backend (the MLP fused on the host BLAS on CPU devices)
  libblis-dev libdnnl-dev libxsmm-dev  # further CPU GEMM libraries the host MLP can use per product (tune --host-gemm)
  libcpp-httplib-dev  # `mipnerf-cl view`'s HTTP server
)
test_packages=(
  ccache            # rebuilds after a checkout switch (scripts/build.sh, scripts/test-sanitize.sh use it when found)
  clinfo python3-venv  # scripts/install-intel-opencl.sh: the Intel CPU runtime's stage
  oclgrind          # the OpenCL simulator the kernel tests also run under (tests/oclgrind)
  clang libclang-rt-dev  # the sanitizer build and the fuzz targets (scripts/test-sanitize.sh, scripts/fuzz.sh)
  libopenmpi-dev openmpi-bin  # mpirun: data-parallel training and sharded rendering (optional at build time)
  colmap            # `dataset from-photos` (CPU SIFT); optional for users: without it that command says what to install
  chromium chromium-driver  # the browser stage: `mipnerf-cl view` in headless Chromium (tests/browser)
)
for argument in "$@"; do
  case "$argument" in
    --for-tests) packages+=("${test_packages[@]}") ;;
    --with-colmap) packages+=(colmap) ;;
    -*) echo "install-deps: unknown option '$argument' (--with-colmap, --for-tests, or package names)" >&2; exit 2 ;;
    *) packages+=("$argument") ;;
  esac
done

missing=()
for package in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$package")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages are installed"
  exit 0
fi

sudo=""
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "install-deps: run as root or install sudo" >&2; exit 1; }
  sudo="sudo"
fi
echo "install-deps: installing ${missing[*]}"
$sudo env DEBIAN_FRONTEND=noninteractive apt-get update -qq
$sudo env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}"
