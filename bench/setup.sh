#!/usr/bin/env bash
# Installs what the study scripts in bench/ need beyond the build's own packages (scripts/install-deps.sh):
# matplotlib, which draws bench/studies/accuracy_time.py's plot. The project's build and tests do not need it.
# Through scripts/install-deps.sh (idempotent, non-interactive, sudo when not root), with the build's packages.
set -euo pipefail
exec "$(dirname "$0")/../scripts/install-deps.sh" python3-matplotlib
