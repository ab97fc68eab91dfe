#!/usr/bin/env bash
# The test job: set up, then run every test with the Khronos validation layer on
# (any validation message fails a test).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
# The central-model exports are checked against OpenCV itself (tests/cli/calibrate.rs runs
# scripts/check-omnidir.py): a project-local venv with OpenCV's contrib wheel, made once and
# moved into place only whole (a failed pip install must not look like a ready venv).
if [ ! -x .venv-check/bin/python ] || ! .venv-check/bin/python -c "import cv2" 2>/dev/null; then
    if ! python3 -m venv --help >/dev/null 2>&1 || ! python3 -c "import ensurepip" 2>/dev/null; then
        echo "test: installing python3-venv (for the OpenCV check's venv)" >&2
        if [ "$(id -u)" -eq 0 ]; then apt-get update -qq && apt-get install -y -qq python3-venv
        else sudo apt-get update -qq && sudo apt-get install -y -qq python3-venv
        fi
    fi
    rm -rf .venv-check .venv-check.new
    python3 -m venv .venv-check.new
    .venv-check.new/bin/pip install --quiet opencv-contrib-python-headless
    # The venv's scripts name their folder: made as .new, it is rebuilt in place.
    mv .venv-check.new .venv-check
    python3 -m venv --upgrade .venv-check >/dev/null
fi
# Every check must run here: a test that cannot make one (a missing tool or driver) fails
# instead of passing without checking (tests/common: `skip`). Checks that do not apply to a
# device (it lacks a feature) are allowed; both kinds are logged and counted below.
export SPECCHIO_REQUIRE_TOOL_CHECKS=1
export SPECCHIO_VALIDATE=1
export SPECCHIO_SKIP_LOG="$PWD/target/test-skips.log"
mkdir -p target
rm -f "$SPECCHIO_SKIP_LOG"
status=0
cargo test --locked --workspace || status=$?
skipped=0
not_applicable=0
if [ -f "$SPECCHIO_SKIP_LOG" ]; then
    skipped=$(grep -c '^skipped' "$SPECCHIO_SKIP_LOG" || true)
    not_applicable=$(grep -c '^not-applicable' "$SPECCHIO_SKIP_LOG" || true)
    sed 's/^/test: /' "$SPECCHIO_SKIP_LOG" >&2
fi
echo "test: $skipped check(s) skipped, $not_applicable not applicable to a device (listed above)" >&2
if [ "$skipped" -gt 0 ]; then
    echo "test: $skipped check(s) that must run could not (listed above as 'skipped')" >&2
    [ "$status" -ne 0 ] || status=1
fi
exit "$status"
