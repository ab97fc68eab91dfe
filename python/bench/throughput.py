"""The Python package's throughput against the command's, and Ray's speed-up (a benchmark,
not a test: docs/python.md reports what it printed).

    .venv/bin/python python/bench/throughput.py [--scene scenes/thesis-room.toml]
        [--poses 48] [--bin target/release/specchio] [--workers 1,2] [--no-ray]

Measures, on the same trajectory (a circle of `--poses` poses about the room's centre):
1. `specchio dataset` (the command) and `specchio.dataset` (Python, one process): frames/s of
   the same work, the same files (checked byte for byte);
2. `Renderer.render_batch` into reused buffers: sensor images/s with every layer as arrays,
   no files;
3. `specchio.dataset(..., ray=True)` with each worker count of `--workers`, each worker's
   lavapipe on one thread (LP_NUM_THREADS=1): frames/s and the speed-up over the first.
Build the wheel with `--release` first (docs/python.md): a dev build measures the wrong thing.
"""

from __future__ import annotations

import argparse
import math
import os
import pathlib
import shutil
import subprocess
import tempfile
import time

import numpy as np

import specchio


def circle(scene: specchio.Scene, n: int, radius: float) -> np.ndarray:
    x, y, z = scene.mirror_position
    t = np.linspace(0.0, 2.0 * math.pi, n, endpoint=False)
    return np.stack([x + radius * np.cos(t), np.full(n, y), z + radius * np.sin(t), np.degrees(t)], axis=1)


def write_csv(path: pathlib.Path, poses: np.ndarray) -> None:
    rows = ["time,x,y,z,heading"] + [f"0,{x!r},{y!r},{z!r},{h!r}" for x, y, z, h in poses.tolist()]
    path.write_text("\n".join(rows) + "\n")


def tree(folder: pathlib.Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def timed(f) -> float:
    start = time.perf_counter()
    f()
    return time.perf_counter() - start


def main() -> None:
    args = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    args.add_argument("--scene", default="scenes/thesis-room.toml")
    args.add_argument("--poses", type=int, default=48)
    args.add_argument("--radius", type=float, default=1.0, help="of the circle, metres")
    args.add_argument("--bin", default="target/release/specchio")
    args.add_argument("--workers", default="1,2")
    args.add_argument("--no-ray", action="store_true")
    a = args.parse_args()
    scene = specchio.Scene(a.scene)
    poses = circle(scene, a.poses, a.radius)
    work = pathlib.Path(tempfile.mkdtemp(prefix="specchio-bench-"))
    try:
        csv = work / "robot.csv"
        write_csv(csv, poses)
        n = len(poses)
        cli_s = timed(lambda: subprocess.run(
            [a.bin, "dataset", a.scene, "--trajectory", str(csv), "--out", str(work / "cli")],
            check=True, capture_output=True))
        py_s = timed(lambda: specchio.dataset(a.scene, csv, work / "py"))
        same = tree(work / "cli") == tree(work / "py")
        print(f"dataset, {n} frames of {a.scene}: command {n / cli_s:.2f} frames/s, "
              f"Python {n / py_s:.2f} frames/s ({100 * cli_s / py_s:.0f} % of the command's); "
              f"the same files: {same}")
        with specchio.Renderer(scene) as r:
            out = r.render_batch(poses[:1])  # warm: pipelines made, buffers of one pose
            out = None
            batch_s = timed(lambda: r.render_batch(poses))
            buffers = r.render_batch(poses)
            reuse_s = timed(lambda: r.render_batch(poses, out=buffers))
            print(f"render_batch on {r.device} ({r.lookup}, {r.ground_truth}): "
                  f"{n / batch_s:.2f} images/s with new arrays, {n / reuse_s:.2f} into reused ones")
        if a.no_ray:
            return
        import ray
        from specchio.ray import init_options

        counts = [int(w) for w in a.workers.split(",")]
        # Started once, so that each run's time is the dataset's, not Ray's start-up.
        ray.init(num_cpus=max(counts), **init_options())
        rates = []
        for w in counts:
            out_dir = work / f"ray{w}"
            s = timed(lambda: specchio.dataset(a.scene, csv, out_dir, ray=True, workers=w,
                                               shard_size=max(1, n // (4 * w)),
                                               worker_env={"LP_NUM_THREADS": "1"}))
            same = tree(out_dir) == tree(work / "py")
            rates.append(n / s)
            print(f"Ray, {w} worker(s), one lavapipe thread each: {n / s:.2f} frames/s "
                  f"(speed-up {rates[-1] / rates[0]:.2f}), the same files: {same}")
        ray.shutdown()
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
