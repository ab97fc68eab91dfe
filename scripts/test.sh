#!/usr/bin/env bash
# The test job: set up, then run every test with the Khronos validation layer on
# (any validation message fails a test).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
# The central-model exports are checked against OpenCV itself (tests/cli/calibrate.rs runs
# scripts/check-omnidir.py): a project-local venv with OpenCV's contrib wheel.
scripts/python-venv.sh .venv-check "import cv2" opencv-contrib-python-headless
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
# The Python package (python/): its wheel built by maturin with the tests' profile (the engine
# is built already), installed into .venv, and its tests (python/tests/) run by pytest, on
# the same devices and with the same validation layer. They compare with the command's own
# output (SPECCHIO_BIN, built by `cargo test` for its tests).
rm -rf target/wheels
.venv/bin/python -m maturin build --quiet --locked --profile dev -m python/Cargo.toml -o target/wheels
.venv/bin/python -m pip install --quiet --disable-pip-version-check --force-reinstall --no-deps target/wheels/specchio-*.whl
# (cargo adds the project-local SwiftShader for its tests, .cargo/config.toml; pytest too.)
# The Ray tests start a local Ray, whose processes talk over the machine's network address:
# where we may (root), they run in a network namespace of their own with only the loopback
# interface, so that no test traffic leaves it.
offline=()
if unshare --net true 2>/dev/null && command -v ip >/dev/null; then
    offline=(unshare --net sh -c 'ip link set lo up && exec "$@"' sh)
fi
VK_ADD_DRIVER_FILES="${VK_ADD_DRIVER_FILES:-$PWD/.drivers/swiftshader/vk_swiftshader_icd.json}" \
SPECCHIO_BIN="$PWD/target/debug/specchio" \
    "${offline[@]}" .venv/bin/python -m pytest -q -p no:cacheprovider python/tests || status=$?
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
