#!/usr/bin/env python3
"""Side-by-side speed of `specchio reference` and Mitsuba 3 on the same scene.

The scene is scenes/test/six-colour-room.toml seen by its sensor: a 10 m cube room whose six
walls are flat colours, unlit, and a mirror sphere of radius 1 m at its centre; the sensor sits
2.5 m below the mirror looking up (+Y, image up -Z), 60 degree vertical field of view. specchio's
reference shows each wall's albedo, seen directly or in the mirror; in Mitsuba the walls are
area emitters with that radiance and no reflectance, and the sphere a perfect conductor, so a
camera path that meets the mirror needs exactly one more ray, as in specchio.

Two Mitsuba integrators are timed: its `path` integrator (max depth 3) and a minimal one written
here that does exactly the reference's work per camera sample (a camera ray; on the mirror, one
reflected ray; the emitter's radiance where it lands). Both render with a box filter at the
given samples per pixel, after a warm-up render that compiles their kernels.

Usage (Mitsuba from PyPI in a throwaway venv; its LLVM backend needs libLLVM >= 16, e.g.
Debian's libllvm19):
    python3 -m venv /tmp/mi && /tmp/mi/bin/pip install mitsuba numpy
    apt-get install libllvm19
    cargo build --release -p specchio-cli
    /tmp/mi/bin/python scripts/mitsuba-compare.py [--size 512] [--spp 16] [--threads 2] [--runs 3]
The binary is target/release/specchio, or $SPECCHIO_BIN when set (a build with its own
CARGO_TARGET_DIR).
It prints camera paths per second for each renderer and the mean absolute difference of the
Mitsuba images from specchio's (the same pixels, so the work is the same).
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

import drjit as dr
import mitsuba as mi
import numpy as np

# The LLVM backend, the one that runs on a CPU; chosen before any Mitsuba type is used.
mi.set_variant("llvm_ad_rgb")

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENE = os.path.join(ROOT, "scenes", "test", "six-colour-room.toml")
# +X red, -X cyan, +Y green, -Y magenta, +Z blue, -Z yellow (the scene file's colours).
WALLS = {
    "px": ([1, 0, 0], [1, 0, 0]),
    "nx": ([-1, 0, 0], [0, 1, 1]),
    "py": ([0, 1, 0], [0, 1, 0]),
    "ny": ([0, -1, 0], [1, 0, 1]),
    "pz": ([0, 0, 1], [0, 0, 1]),
    "nz": ([0, 0, -1], [1, 1, 0]),
}


def wall(axis, colour):
    """A 10 m square at 5 m along `axis`, facing the room's centre, emitting `colour`."""
    n = np.array(axis, dtype=float)
    # Mitsuba's rectangle spans [-1, 1]^2 in z = 0 and faces +z.
    to_world = mi.ScalarTransform4f().look_at(origin=(5 * n).tolist(), target=[0, 0, 0],
                                               up=[0, 1, 0] if abs(n[1]) < 0.5 else [0, 0, 1])
    return {
        "type": "rectangle",
        "to_world": to_world @ mi.ScalarTransform4f().scale([5, 5, 1]),
        "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0, 0, 0]}},
        "emitter": {"type": "area", "radiance": {"type": "rgb", "value": colour}},
    }


def scene_dict(size, spp, integrator):
    d = {
        "type": "scene",
        "integrator": integrator,
        "sensor": {
            "type": "perspective",
            "fov": 60,
            "fov_axis": "y",
            "to_world": mi.ScalarTransform4f().look_at(origin=[0, -2.5, 0], target=[0, 0, 0],
                                                        up=[0, 0, -1]),
            "film": {"type": "hdrfilm", "width": size, "height": size,
                     "rfilter": {"type": "box"}, "pixel_format": "rgb"},
            "sampler": {"type": "independent", "sample_count": spp},
        },
        "mirror": {"type": "sphere", "radius": 1.0, "center": [0, 0, 0],
                   "bsdf": {"type": "conductor", "material": "none"}},
    }
    for name, (axis, colour) in WALLS.items():
        d[name] = wall(axis, colour)
    return d


class Minimal(mi.SamplingIntegrator):
    """Exactly the reference's work: one camera ray, one reflected ray on the mirror."""

    def __init__(self, props):
        mi.SamplingIntegrator.__init__(self, props)

    def sample(self, scene, sampler, ray, medium=None, active=True):
        si = scene.ray_intersect(ray, active)
        flags = si.bsdf().flags()
        on_mirror = si.is_valid() & mi.has_flag(flags, mi.BSDFFlags.DeltaReflection)
        direct = si.emitter(scene).eval(si, si.is_valid() & ~on_mirror)
        reflected = si.spawn_ray(si.to_world(mi.reflect(si.wi)))
        si2 = scene.ray_intersect(reflected, on_mirror)
        mirrored = si2.emitter(scene).eval(si2, on_mirror & si2.is_valid())
        result = dr.select(on_mirror, mirrored, direct)
        return result, si.is_valid(), []


def time_mitsuba(scene, spp, runs):
    mi.render(scene, spp=spp)  # warm-up: compiles the kernels
    best, image = None, None
    for _ in range(runs):
        start = time.perf_counter()
        image = mi.render(scene, spp=spp)
        dr.eval(image)
        dr.sync_thread()
        elapsed = time.perf_counter() - start
        best = elapsed if best is None else min(best, elapsed)
    return best, np.array(image)


def time_specchio(size, spp, runs):
    # SPECCHIO_BIN overrides the binary (e.g. a build with its own CARGO_TARGET_DIR).
    binary = os.environ.get("SPECCHIO_BIN") or os.path.join(ROOT, "target", "release", "specchio")
    best, folder = None, tempfile.mkdtemp(prefix="specchio-mitsuba-")
    with open(SCENE) as f:
        text = f.read()
    scene = os.path.join(folder, "scene.toml")
    with open(scene, "w") as f:
        f.write(text.replace("[sensor]\n", f"[sensor]\nresolution = [{size}, {size}]\n", 1)
                .replace("[observer]\n", "[observer]\nresolution = [8, 8]\n", 1))
    for run in range(runs + 1):
        out = os.path.join(folder, "out")
        subprocess.run([binary, "reference", scene, "--out", out, "--spp", str(spp)],
                       check=True, capture_output=True)
        with open(os.path.join(out, "reference.json")) as f:
            record = json.load(f)
        trace_s = record["cameras"]["sensor"]["trace_ms"] / 1e3
        if run > 0:  # the first run warms the caches
            best = trace_s if best is None else min(best, trace_s)
    return best, os.path.join(out, "sensor.exr")


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--size", type=int, default=512)
    p.add_argument("--spp", type=int, default=16)
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--runs", type=int, default=3)
    a = p.parse_args()
    dr.set_thread_count(a.threads)
    os.environ.setdefault("RAYON_NUM_THREADS", str(a.threads))
    mi.register_integrator("specchio_minimal", lambda props: Minimal(props))
    paths = a.size * a.size * a.spp
    ours_s, ours_exr = time_specchio(a.size, a.spp, a.runs)
    ours = np.array(mi.Bitmap(ours_exr))[:, :, :3]
    print(f"scene: {SCENE} sensor, {a.size}x{a.size}, {a.spp} spp, {a.threads} threads, "
          f"best of {a.runs}")
    print(f"specchio reference : {ours_s * 1e3:8.1f} ms  {paths / ours_s / 1e6:6.2f} M camera paths/s")
    for name, integrator in [("mitsuba minimal", {"type": "specchio_minimal"}),
                             ("mitsuba path", {"type": "path", "max_depth": 3})]:
        scene = mi.load_dict(scene_dict(a.size, a.spp, integrator))
        secs, image = time_mitsuba(scene, a.spp, a.runs)
        diff = float(np.abs(image[:, :, :3] - ours).mean())
        print(f"{name:19}: {secs * 1e3:8.1f} ms  {paths / secs / 1e6:6.2f} M camera paths/s  "
              f"(specchio/mitsuba speed {secs / ours_s:.2f}x; mean |difference| {diff:.4f})")


if __name__ == "__main__":
    sys.exit(main())
