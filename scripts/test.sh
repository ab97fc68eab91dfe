#!/usr/bin/env bash
# The test job: set up, then run every test with the Khronos validation layer on
# (any validation message fails a test).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
export SPECCHIO_VALIDATE=1
cargo test --locked --workspace
