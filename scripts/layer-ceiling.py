#!/usr/bin/env python3
"""What a cube map rendered at the mirror's centre can show at best, with one or more depth layers.

The reference's object layer says, per mirror pixel, how many surfaces hide what the reflected
ray really meets from the mirror's centre (b channel; 0 = in the cube's first layer). This script
takes a `specchio render --directions` of a lookup that is exact wherever it can be
(distance-exact) and one of a single-layer lookup (distance), and builds for k layers the image
of a lookup exact on every pixel whose surface is in the first k layers and showing the
single-layer answer on the others; `specchio compare` gives its FLIP against the reference. It
also splits the lookups' angular errors into pixels the cube stores and pixels it cannot.

Usage (the EXR reader is Mitsuba's, in the venv of scripts/mitsuba-compare.py):
    specchio reference SCENE --out R --spp 1
    specchio render SCENE --out E --lookup distance-exact --directions --cube-size 512
    specchio render SCENE --out D --lookup distance --directions --cube-size 512
    VENV/bin/python scripts/layer-ceiling.py R E D [more renders ...]
"""
import os
import subprocess
import sys
import tempfile

import mitsuba as mi
import numpy as np

mi.set_variant("scalar_rgb")
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BINARY = os.environ.get("SPECCHIO_BIN") or os.path.join(ROOT, "target", "release", "specchio")


def load(path):
    return np.array(mi.Bitmap(path))


def flip(image, reference):
    out = subprocess.run([BINARY, "compare", image, reference], check=True,
                         capture_output=True, text=True).stdout
    return next(line.split()[-1] for line in out.splitlines() if "FLIP mean" in line)


def angular(render, reference_dir):
    d = load(os.path.join(render, "sensor.direction.exr"))[:, :, :3]
    r = reference_dir[:, :, :3]
    norms = np.maximum(np.linalg.norm(d, axis=2) * np.linalg.norm(r, axis=2), 1e-12)
    return np.degrees(np.arccos(np.clip((d * r).sum(axis=2) / norms, -1.0, 1.0)))


def main():
    if len(sys.argv) < 4:
        sys.exit(__doc__)
    ref, exact, single = sys.argv[1:4]
    obj = load(os.path.join(ref, "sensor.object.exr"))
    mirror = obj[:, :, 1] == 1.0
    hidden = obj[:, :, 2]
    reference = os.path.join(ref, "sensor.exr")
    exact_img = load(os.path.join(exact, "sensor.exr"))
    single_img = load(os.path.join(single, "sensor.exr"))
    print(f"mirror pixels: {mirror.sum()}")
    print("| layers | mirror pixels whose surface they hold | best FLIP with that many layers |")
    print("|---:|---:|---:|")
    with tempfile.TemporaryDirectory() as tmp:
        for k in [1, 2, 3, 5, 8]:
            composed = exact_img.copy()
            beyond = mirror & (hidden >= k)
            composed[beyond] = single_img[beyond]
            path = os.path.join(tmp, f"layers{k}.exr")
            mi.Bitmap(composed.astype(np.float32)).write(path)
            share = 100.0 * (mirror & (hidden < k)).sum() / mirror.sum()
            print(f"| {k} | {share:.1f} % | {flip(path, reference)} |")
    # One texel of the cube's face (the renders above use 512; FACE=N for another size).
    texel = 90.0 / int(os.environ.get("FACE", "512"))
    reference_dir = load(os.path.join(ref, "sensor.direction.exr"))
    print(f"\n| render | pixels the cube stores: beyond one texel ({texel:.3f} deg) |")
    print("|---|---:|")
    stored = mirror & (hidden == 0)
    for render in sys.argv[3:]:
        a = angular(render, reference_dir)[stored]
        print(f"| {render} | {100.0 * (a > texel).mean():.1f} % |")


if __name__ == "__main__":
    sys.exit(main())
