#!/usr/bin/env bash
# Creates .venv in the repository root with the Python protocol peers the tests use.
# Idempotent: does nothing when the venv already has the pinned packages.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
venv="$root/.venv"
req="$root/scripts/requirements-peers.txt"
stamp="$venv/.requirements-stamp"
if [ -f "$stamp" ] && cmp -s "$req" "$stamp"; then
  exit 0
fi
python3 -m venv "$venv"
"$venv/bin/pip" install --quiet --disable-pip-version-check -r "$req"
cp "$req" "$stamp"
