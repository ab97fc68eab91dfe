#!/usr/bin/env bash
# The test job: set up, then run every test with the Khronos validation layer on
# (any validation message fails a test).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
# The central-model exports are checked against OpenCV itself (tests/calibrate.rs runs
# scripts/check-omnidir.py): a project-local venv with OpenCV's contrib wheel, made once.
if [ ! -x .venv-check/bin/python ]; then
    python3 -m venv .venv-check
    .venv-check/bin/pip install --quiet opencv-contrib-python-headless
fi
export SPECCHIO_REQUIRE_TOOL_CHECKS=1
export SPECCHIO_VALIDATE=1
cargo test --locked --workspace
