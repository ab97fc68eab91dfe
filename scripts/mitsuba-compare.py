#!/usr/bin/env python3
"""Side-by-side speed of `specchio reference` and Mitsuba 3 on the same scene.

The scene is scenes/test/six-colour-room.toml seen by its sensor: a 10 m cube room whose six
walls are flat colours, unlit, and a mirror sphere of radius 1 m at its centre; the sensor sits
2.5 m below the mirror looking up (+Y, image up -Z), 60 degree vertical field of view. specchio's
reference shows each wall's albedo, seen directly or in the mirror; in Mitsuba the walls are
area emitters with that radiance and no reflectance, and the sphere a perfect conductor, so a
camera path that meets the mirror needs exactly one more ray, as in specchio.

`--scene objects` adds three flat-coloured boxes to that room (36 triangles: a pole from floor
to ceiling and two crates, all seen in the mirror), written into a copy of the scene file for
specchio and as emitting cubes for Mitsuba: the case where the reference's object BVH is
entered by every ray.

The renderers run interleaved (specchio, Mitsuba minimal, Mitsuba path, then again), so that a
change in the machine's load hits all of them alike; the ratios are per round, and the script
prints their median and range as well as each renderer's best time.

Two Mitsuba integrators are timed: its `path` integrator (max depth 3) and a minimal one written
here that does exactly the reference's work per camera sample (a camera ray; on the mirror, one
reflected ray; the emitter's radiance where it lands). Both render with a box filter at the
given samples per pixel, after a warm-up render that compiles their kernels.

Usage (Mitsuba from PyPI in a throwaway venv; its LLVM backend needs libLLVM >= 16, e.g.
Debian's libllvm19):
    python3 -m venv /tmp/mi && /tmp/mi/bin/pip install mitsuba numpy
    apt-get install libllvm19
    cargo build --release -p specchio-cli
    /tmp/mi/bin/python scripts/mitsuba-compare.py [--scene six-colour|objects] [--size 512]
        [--spp 16] [--threads 2] [--runs 5]
The binary is target/release/specchio, or $SPECCHIO_BIN when set (a build with its own
CARGO_TARGET_DIR).
It prints camera paths per second for each renderer and the mean absolute difference of the
Mitsuba images from specchio's (the same pixels, so the work is the same).
"""
import argparse
import json
import os
import statistics
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


# --scene objects: (name, centre, size, colour), the same in both renderers. Every box stays
# clear of the mirror (radius 1 at the origin) and inside the room (-5..5 on every axis).
BOXES = [
    ("pole", [2.0, 0.0, 1.5], [0.2, 10.0, 0.2], [1.0, 0.5, 0.0]),
    ("crate", [-2.5, -4.0, -2.0], [1.5, 2.0, 1.5], [0.5, 0.0, 1.0]),
    ("shelf", [1.0, 3.0, -3.0], [2.0, 0.3, 1.0], [1.0, 1.0, 1.0]),
]


def emitting(to_world, colour, shape):
    return {
        "type": shape,
        "to_world": to_world,
        "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0, 0, 0]}},
        "emitter": {"type": "area", "radiance": {"type": "rgb", "value": colour}},
    }


def wall(axis, colour):
    """A 10 m square at 5 m along `axis`, facing the room's centre, emitting `colour`."""
    n = np.array(axis, dtype=float)
    # Mitsuba's rectangle spans [-1, 1]^2 in z = 0 and faces +z.
    to_world = mi.ScalarTransform4f().look_at(origin=(5 * n).tolist(), target=[0, 0, 0],
                                               up=[0, 1, 0] if abs(n[1]) < 0.5 else [0, 0, 1])
    return emitting(to_world @ mi.ScalarTransform4f().scale([5, 5, 1]), colour, "rectangle")


def scene_dict(size, spp, integrator, objects):
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
    for name, centre, size_m, colour in BOXES if objects else []:
        # Mitsuba's cube spans [-1, 1]^3.
        to_world = (mi.ScalarTransform4f().translate(centre)
                    @ mi.ScalarTransform4f().scale([x / 2 for x in size_m]))
        d[name] = emitting(to_world, colour, "cube")
    return d


def specchio_scene(folder, size, objects):
    """A copy of the six-colour room at the given sensor size, with the boxes when asked."""
    with open(SCENE) as f:
        text = f.read()
    text = (text.replace("[sensor]\n", f"[sensor]\nresolution = [{size}, {size}]\n", 1)
            .replace("[observer]\n", "[observer]\nresolution = [8, 8]\n", 1))
    for name, centre, size_m, colour in BOXES if objects else []:
        text += (f'\n[[materials]]\nname = "{name}"\ntype = "color"\ncolor = {colour}\n'
                 f'\n[[objects]]\nname = "{name}"\nshape = "box"\nsize = {size_m}\n'
                 f'position = {centre}\nmaterial = "{name}"\n')
    path = os.path.join(folder, "scene.toml")
    with open(path, "w") as f:
        f.write(text)
    return path


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


def run_mitsuba(scene, spp):
    """One timed render (the kernels compiled by an earlier warm-up render)."""
    start = time.perf_counter()
    image = mi.render(scene, spp=spp)
    dr.eval(image)
    dr.sync_thread()
    return time.perf_counter() - start, np.array(image)


def run_specchio(scene, folder, spp):
    """One reference render; its own figure for the sensor's trace (camera paths only)."""
    # SPECCHIO_BIN overrides the binary (e.g. a build with its own CARGO_TARGET_DIR).
    binary = os.environ.get("SPECCHIO_BIN") or os.path.join(ROOT, "target", "release", "specchio")
    out = os.path.join(folder, "out")
    subprocess.run([binary, "reference", scene, "--out", out, "--spp", str(spp)],
                   check=True, capture_output=True)
    with open(os.path.join(out, "reference.json")) as f:
        record = json.load(f)
    return record["cameras"]["sensor"]["trace_ms"] / 1e3, os.path.join(out, "sensor.exr")


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--scene", choices=["six-colour", "objects"], default="six-colour")
    p.add_argument("--size", type=int, default=512)
    p.add_argument("--spp", type=int, default=16)
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--runs", type=int, default=5)
    a = p.parse_args()
    if a.runs < 1 or a.size < 1 or a.spp < 1 or a.threads < 1:
        p.error("--runs, --size, --spp and --threads must be at least 1")
    dr.set_thread_count(a.threads)
    os.environ.setdefault("RAYON_NUM_THREADS", str(a.threads))
    mi.register_integrator("specchio_minimal", lambda props: Minimal(props))
    objects = a.scene == "objects"
    folder = tempfile.mkdtemp(prefix="specchio-mitsuba-")
    ours_scene = specchio_scene(folder, a.size, objects)
    theirs = {name: mi.load_dict(scene_dict(a.size, a.spp, integrator, objects))
              for name, integrator in [("mitsuba minimal", {"type": "specchio_minimal"}),
                                       ("mitsuba path", {"type": "path", "max_depth": 3})]}
    # Warm-up: Mitsuba compiles its kernels, specchio fills the caches.
    images = {name: run_mitsuba(scene, a.spp)[1] for name, scene in theirs.items()}
    _, ours_exr = run_specchio(ours_scene, folder, a.spp)
    times = {name: [] for name in ["specchio reference", *theirs]}
    for _ in range(a.runs):
        times["specchio reference"].append(run_specchio(ours_scene, folder, a.spp)[0])
        for name, scene in theirs.items():
            secs, images[name] = run_mitsuba(scene, a.spp)
            times[name].append(secs)
    ours = np.array(mi.Bitmap(ours_exr))[:, :, :3]
    paths = a.size * a.size * a.spp
    print(f"scene: {a.scene} ({SCENE} sensor{', with ' + str(12 * len(BOXES)) + ' object triangles' if objects else ''}), "
          f"{a.size}x{a.size}, {a.spp} spp, {a.threads} threads, {a.runs} interleaved rounds")
    for name, secs in times.items():
        best = min(secs)
        line = f"{name:19}: best {best * 1e3:8.1f} ms  {paths / best / 1e6:6.2f} M camera paths/s"
        if name in theirs:
            # Per round: Mitsuba's time over specchio's in the same round (> 1: specchio faster).
            ratios = sorted(t / o for t, o in zip(secs, times["specchio reference"]))
            median = statistics.median(ratios)
            diff = float(np.abs(images[name][:, :, :3] - ours).mean())
            line += (f"  specchio/mitsuba speed median {median:.2f}x "
                     f"(rounds {ratios[0]:.2f}-{ratios[-1]:.2f}x); mean |difference| {diff:.4f}")
        print(line)


if __name__ == "__main__":
    sys.exit(main())
