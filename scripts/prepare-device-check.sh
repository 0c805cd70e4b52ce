#!/usr/bin/env bash
# Prepares the folder a device call carries for scripts/device-check.sh (docs/devices.md, "A session lent a GPU"):
#   FOLDER/bundle    scripts/bundle.sh's bundle (its own Release build in build-bundle/, 10-20 minutes on 2 cores the
#                    first time, minutes with ccache after)
#   FOLDER/official  google/mipnerf at the pinned commit, from a git repository (a `fetch github:google/mipnerf`
#                    mirror or a clone) or a folder holding it; only read there, never part of the repository
#   FOLDER/wheels    gin-config's wheel (pure Python, from PyPI): the GPU image's python has JAX, flax, optax, absl
#                    and Pillow but not gin, and nothing can be installed there from the network
# then prints the folder's size and the device call to make. Run it in the checkout the session was started in: a
# device call sends that checkout, also when a helper calls from another worktree. FOLDER (default .device-check) is
# ignored by git (.gitignore), so it travels only when the call's `carry` names it.
#
# Usage: scripts/prepare-device-check.sh --official GIT_OR_FOLDER [--folder DIR] [--bundle-from-build BUILD_DIR]
#   --bundle-from-build  pack this build instead of building the bundle configuration (it must fit: --max-mib 48)
set -euo pipefail
cd "$(dirname "$0")/.."
official_commit=84c969e0a623edd183b75693aed72a7e7c22902d
gin_wheel="gin-config==0.5.0"
folder=.device-check
official_source=""
from_build=()
while [ $# -gt 0 ]; do
  case "$1" in
    --official) official_source="${2:?}"; shift 2 ;;
    --folder) folder="${2:?}"; shift 2 ;;
    --bundle-from-build) from_build=(--from-build "${2:?}"); shift 2 ;;
    -h|--help) sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
    *) echo "prepare-device-check: unknown argument '$1' (--official, --folder, --bundle-from-build)" >&2; exit 2 ;;
  esac
done
[ -n "$official_source" ] || {
  echo "prepare-device-check: --official names google/mipnerf: a git repository (e.g. the fetch tool's mirror of" \
    "github:google/mipnerf) or a folder holding train.py and internal/ at commit $official_commit" >&2
  exit 2
}
mkdir -p "$folder"

./scripts/bundle.sh "${from_build[@]}" "$folder/bundle"

rm -rf "$folder/official"
mkdir -p "$folder/official"
if git --git-dir="$official_source" rev-parse --verify -q "$official_commit^{commit}" > /dev/null 2>&1; then
  git --git-dir="$official_source" archive "$official_commit" | tar -x -C "$folder/official"
elif git -C "$official_source" rev-parse --verify -q "$official_commit^{commit}" > /dev/null 2>&1; then
  git -C "$official_source" archive "$official_commit" | tar -x -C "$folder/official"
elif [ -f "$official_source/internal/models.py" ]; then
  echo "prepare-device-check: $official_source is not a git repository holding $official_commit: copying it as it is"
  (cd "$official_source" && tar --exclude=.git -cf - .) | tar -x -C "$folder/official"
else
  echo "prepare-device-check: --official $official_source holds neither commit $official_commit nor internal/models.py" >&2
  exit 1
fi
echo "$official_commit" > "$folder/official/COMMIT"

rm -rf "$folder/wheels"
python3 -m pip download -q --no-deps --only-binary=:all: --python-version 3.12 --implementation py \
  -d "$folder/wheels" "$gin_wheel"

tracked=$(git ls-files -z | xargs -0 du -cb 2>/dev/null | tail -n 1 | cut -f1)
carried=$(du -sb "$folder" | cut -f1)
mib() { awk -v b="$1" 'BEGIN { printf "%.1f MiB", b / 1048576 }'; }
echo "prepare-device-check: $folder holds $(mib "$carried") (bundle $(du -sb "$folder/bundle" | cut -f1 | { read -r b; mib "$b"; }))," \
  "the tracked tree $(mib "$tracked"): $(mib $((carried + tracked))) of the 64 MiB a call carries (untracked files that" \
  "git does not ignore travel too: git status --short)."
echo "The device call (the device tool's run):"
echo "  command: scripts/device-check.sh    carry: [\"$folder\"]    timeout_s: 540"
