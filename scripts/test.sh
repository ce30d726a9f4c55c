#!/usr/bin/env bash
# The test command of the README: installs what is missing, then runs every test.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
cargo test --all-targets 2>&1
