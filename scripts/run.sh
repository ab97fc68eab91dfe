#!/usr/bin/env bash
# The main job: set up, build, and render the thesis's scene on the default device.
# Usage: scripts/run.sh [SCENE] [OUT]   (defaults: scenes/thesis-room.toml out/thesis-room)
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
cargo build --release --locked -p specchio-cli
scene=${1:-scenes/thesis-room.toml}
out=${2:-out/$(basename "$scene" .toml)}
target/release/specchio info
target/release/specchio render "$scene" --out "$out" --frames 1
echo "open $out/views.png (observer | sensor), $out/render.json for settings and timings"
