#!/usr/bin/env bash
# Runs the whole test suite: installs the Python protocol peers and the headless browser (once),
# then every test of the workspace.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup-peers.sh
scripts/setup-browser.sh
cargo test --workspace "$@"
