#!/usr/bin/env bash
# The main job: set up, build, and run the benchmark (speed against error of every cube fill
# method) on the default scene set, then render the thesis's scene.
# Usage: scripts/run.sh [BENCH ARGUMENTS...]   e.g. scripts/run.sh --quick
#        (default: every scene of the default set; results in out/bench/)
set -euo pipefail
cd "$(dirname "$0")/.."
# Only what the main job uses (no X, Wayland, FUSE or Python; SwiftShader when asked for).
scripts/setup.sh --main-job "$@"
# Without the viewer, which the main job does not run (a third of a fresh build); `cargo build
# --release -p specchio-cli` adds it (docs/viewer.md).
cargo build --release --locked -p specchio-cli --no-default-features
bin=target/release/specchio
mkdir -p out/bench
$bin info
$bin bench "$@" --json out/bench/bench.json --csv out/bench/bench.csv --plot out/bench/bench.svg \
    --bmf out/bench/bench.bmf.json
$bin render scenes/thesis-room.toml --out out/thesis-room --frames 1
echo "benchmark: out/bench/bench.json, bench.csv, bench.svg (speed against error), bench.bmf.json (Bencher);"
echo "views: out/thesis-room/views.png (observer | sensor), out/thesis-room/render.json"
