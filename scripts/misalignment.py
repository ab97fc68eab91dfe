#!/usr/bin/env python3
"""How a central mirror stops being central when its camera is off the focus.

A hyperbolic mirror is central only with its camera's pinhole exactly at the outer focus. This
script moves the camera of a scene's hyperboloid off it, by shifts across the axis (0.1 mm,
1 mm, 1 cm, along world X) and tilts of its axis (0.1 and 1 degree, about world X), and
measures for each:

- what `specchio calibrate` makes of it: the unified (omnidir) model's residual angle between
  its rays and the exact ones, the xi it fits, and how far the exact rays pass from the one
  viewpoint the model assumes;
- the plain cube lookup's angular error on the sensor (the cube still rendered at the inner
  focus), from `specchio render --directions` against `specchio reference`.

The scene variants are written into a temporary folder beside links to the scene's textures and
meshes, with the `[sensor]` table's `shift` / `tilt` added; nothing in the repository changes.

A misalignment that takes the mirror's rim out of the image is refused by the scene loader
(the default field of view fits the aligned rim with a 5 % margin); `--fov DEG` gives every
case the same wider field of view instead (a robot's 3 cm mirror moved by 1 cm needs about 40).

Usage:
    cargo build --release -p specchio-cli
    python3 scripts/misalignment.py [scenes/hyperbolic-room.toml] [--fov DEG]
"""

import json
import os
import re
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BINARY = os.path.join(ROOT, "target", "release", "specchio")

CASES = [
    ("aligned", None, None),
    ("shift 0.1 mm", [1e-4, 0, 0], None),
    ("shift 1 mm", [1e-3, 0, 0], None),
    ("shift 1 cm", [1e-2, 0, 0], None),
    ("tilt 0.1 deg", None, 0.1),
    ("tilt 1 deg", None, 1.0),
]


def run(*args):
    result = subprocess.run([BINARY, *args], capture_output=True, text=True)
    if result.returncode != 0:
        sys.exit(f"specchio {' '.join(args)} failed:\n{result.stderr}")
    return result.stdout


def variant(text, shift, tilt, fov):
    """The scene with the sensor's misalignment (and field of view) added to its [sensor]
    table."""
    lines = [] if fov is None else [f"fov_y = {fov!r}"]
    if shift is not None:
        lines.append(f"shift = [{shift[0]!r}, {shift[1]!r}, {shift[2]!r}]")
    if tilt is not None:
        lines.append(f"tilt = {tilt!r}")
    if not lines:
        return text
    if not re.search(r"^\[sensor\]\s*$", text, re.M):
        return text + "\n[sensor]\n" + "\n".join(lines) + "\n"
    return re.sub(r"^\[sensor\]\s*$", "[sensor]\n" + "\n".join(lines), text, count=1, flags=re.M)


def measure(scene, work):
    calib = os.path.join(work, "calibration")
    run("calibrate", scene, "--out", calib)
    record = json.load(open(os.path.join(calib, "calibration.json")))
    render = os.path.join(work, "render")
    run("render", scene, "--out", render, "--directions", "--lookup", "plain")
    reference = os.path.join(work, "reference")
    run("reference", scene, "--out", reference)
    settings = json.load(open(os.path.join(render, "render.json")))["settings"]
    face_size = str(settings["cube"]["face_size_px"])
    angular = json.loads(
        run(
            "compare",
            "--json",
            "--angular",
            face_size,
            os.path.join(render, "sensor.direction.exr"),
            os.path.join(reference, "sensor.direction.exr"),
        )
    )
    return record, angular


def main():
    args = sys.argv[1:]
    fov = None
    if "--fov" in args:
        i = args.index("--fov")
        fov = float(args[i + 1])
        del args[i : i + 2]
    source = os.path.abspath(args[0] if args else os.path.join(ROOT, "scenes", "hyperbolic-room.toml"))
    text = open(source).read()
    rows = []
    with tempfile.TemporaryDirectory(prefix="specchio-misalignment-") as tmp:
        for folder in ("textures", "meshes"):
            target = os.path.join(os.path.dirname(source), folder)
            if os.path.isdir(target):
                os.symlink(target, os.path.join(tmp, folder))
        for i, (name, shift, tilt) in enumerate(CASES):
            scene = os.path.join(tmp, f"case{i}.toml")
            open(scene, "w").write(variant(text, shift, tilt, fov))
            work = os.path.join(tmp, f"case{i}")
            os.mkdir(work)
            record, angular = measure(scene, work)
            rows.append((name, record, angular))
            print(f"measured {name}", file=sys.stderr)
    fov_text = "the scene's field of view" if fov is None else f"fov_y {fov} degrees"
    print(f"misalignment of {os.path.relpath(source, ROOT)}'s sensor camera, {fov_text} (omnidir: specchio calibrate; plain lookup: render --directions against reference)")
    print(
        f"{'camera':14} {'omnidir residual deg: mean':>27} {'p99':>9} {'max':>9} {'xi':>9} "
        f"{'rays off viewpoint m: max':>26} {'plain lookup deg: p99':>22} {'max':>9} {'p99 texels':>11}"
    )
    for name, record, a in rows:
        r = record["omnidir"]["residual_deg"]
        xi = record["omnidir"]["model"]["xi"]
        off = record["ray_distance_to_viewpoint_m"]["max"]
        print(
            f"{name:14} {r['mean']:27.2e} {r['p99']:9.2e} {r['max']:9.2e} {xi:9.6f} "
            f"{off:26.2e} {a['p99_deg']:22.2e} {a['max_deg']:9.2e} {a['p99_texels']:11.3f}"
        )


if __name__ == "__main__":
    main()
