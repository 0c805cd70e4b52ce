#!/usr/bin/env bash
# Installs what the study scripts in bench/ need beyond the build's own packages (scripts/install-deps.sh):
# matplotlib, which draws bench/accuracy_time.py's plot. The project's build and tests do not need it.
# Idempotent and non-interactive: does nothing when the package is installed; uses sudo when not root.
set -euo pipefail

packages=(python3-matplotlib)

missing=()
for package in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$package")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "bench/setup: ${packages[*]} installed"
  exit 0
fi

sudo=""
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "bench/setup: run as root or install sudo" >&2; exit 1; }
  sudo="sudo"
fi
echo "bench/setup: installing ${missing[*]}"
$sudo env DEBIAN_FRONTEND=noninteractive apt-get update -qq
$sudo env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}"
