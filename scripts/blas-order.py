#!/usr/bin/env python3
"""What the triangle order of a large mesh costs the ray-query lookup on a driver that builds its
bottom-level structure from the order it is given (lavapipe 25.0.x, docs/accuracy.md).

Writes a bumpy sphere of about 100k triangles as OBJ twice, in scan order (rings, then
segments, as a modeller or scanner writes them) and shuffled, stands it in the thesis's room in
front of the mirror, and renders the ray-query lookup with each OBJ and each `--trace-order`
(`given`: the file's order; `split`: the engine's median-split order). Prints the median GPU
time of the sensor view (the traced mirror) per case. Python's standard library only.

Usage: scripts/blas-order.py [--frames N] [--keep DIR]   (after `cargo build --release`)
"""
import argparse
import json
import math
import os
import random
import shutil
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BINARY = os.environ.get("SPECCHIO_BIN") or os.path.join(ROOT, "target", "release", "specchio")
# 322 segments x 160 rings: 2 * 322 * 159 = 102,396 triangles (the issue asks for >= 100k).
SEGMENTS, RINGS = 322, 160


def bumpy_sphere():
    """Vertices and triangles of a unit sphere with bumps (so that its triangles differ)."""
    vertices = []
    for r in range(RINGS + 1):
        theta = math.pi * r / RINGS
        for s in range(SEGMENTS):
            phi = 2.0 * math.pi * s / SEGMENTS
            bump = 1.0 + 0.08 * math.sin(7 * theta) * math.cos(9 * phi)
            vertices.append((bump * math.sin(theta) * math.cos(phi), bump * math.cos(theta),
                             bump * math.sin(theta) * math.sin(phi)))
    triangles = []
    for r in range(RINGS):
        for s in range(SEGMENTS):
            a, b = r * SEGMENTS + s, r * SEGMENTS + (s + 1) % SEGMENTS
            c, d = a + SEGMENTS, b + SEGMENTS
            if r > 0:
                triangles.append((a, b, d))
            if r < RINGS - 1:
                triangles.append((a, d, c))
    return vertices, triangles


def write_obj(path, vertices, triangles):
    with open(path, "w") as f:
        f.writelines(f"v {x:.6f} {y:.6f} {z:.6f}\n" for x, y, z in vertices)
        f.writelines(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in triangles)


def scene_text(mesh):
    """thesis-room with the mesh in front of the mirror (textures resolve from the copy)."""
    with open(os.path.join(ROOT, "scenes", "thesis-room.toml")) as f:
        text = f.read()
    return text + f"""
[[objects]]
name = "bumpy-sphere"
shape = "mesh"
file = "{mesh}"
position = [2.5, 2.0, 0.5]
scale = 1.2
material = "wall-red"
"""


def sensor_ms(scene, order, frames, out):
    subprocess.run([BINARY, "render", scene, "--lookup", "ray-query", "--trace-order", order,
                    "--frames", str(frames), "--out", out], check=True, capture_output=True)
    with open(os.path.join(out, "render.json")) as f:
        return json.load(f)["runs"][0]["summary"]["median_gpu_sensor_ms"]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=5)
    parser.add_argument("--keep", help="write the scenes and renders here instead of a temporary folder")
    args = parser.parse_args()
    work = args.keep or tempfile.mkdtemp(prefix="blas-order-")
    os.makedirs(work, exist_ok=True)
    shutil.copytree(os.path.join(ROOT, "scenes", "textures"), os.path.join(work, "textures"),
                    dirs_exist_ok=True)
    vertices, triangles = bumpy_sphere()
    shuffled = triangles[:]
    random.Random(20261125).shuffle(shuffled)
    print(f"bumpy sphere: {len(triangles)} triangles")
    for name, tris in (("scan", triangles), ("shuffled", shuffled)):
        write_obj(os.path.join(work, f"{name}.obj"), vertices, tris)
        scene = os.path.join(work, f"{name}.toml")
        with open(scene, "w") as f:
            f.write(scene_text(f"{name}.obj"))
        for order in ("given", "split"):
            ms = sensor_ms(scene, order, args.frames, os.path.join(work, f"{name}-{order}"))
            print(f"  mesh in {name:8} order, --trace-order {order:5}: sensor view {ms:8.2f} ms (GPU median)")
    if not args.keep:
        shutil.rmtree(work)


if __name__ == "__main__":
    sys.exit(main())
