#!/usr/bin/env python3
"""Checks `specchio calibrate`'s exports against the tools themselves, not against our code.

Usage: check-omnidir.py DIR   (DIR: the folder `specchio calibrate` wrote)

1. OpenCV: reads opencv_omnidir.yaml with cv2.FileStorage and projects the 3D points of
   check_points.json (points along the exact rays of a grid of mirror pixels, at several
   distances, already in the model's frame) with cv2.omnidir.projectPoints; the pixels must
   equal the ones our Rust model predicted within OPENCV_TOLERANCE_PX.
2. OCamCalib: reads ocamcalib_calib_results.txt as OCamCalib's C `get_ocam_model` does and
   projects the same points with `world2cam`, ported here by us from the published formula
   of Scaramuzza's OCamCalib toolbox (ocam_functions.c); same tolerance.
3. Both against the truth: the pixel each point really lies on. The error per distance is
   printed; near points add the parallax of the one assumed viewpoint to the model's
   directional residual.

Needs numpy and opencv-contrib-python-headless (scripts/test.sh makes .venv-check/).
Exit status 0 when every check passes, 1 otherwise.
"""

import json
import math
import sys
from pathlib import Path

import cv2
import numpy as np

# Both sides compute in float64 from the same 17-digit numbers; what is left is rounding.
OPENCV_TOLERANCE_PX = 1e-6


def read_opencv(path):
    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_READ)
    if not fs.isOpened():
        raise SystemExit(f"{path}: cv2.FileStorage cannot open it")
    K = fs.getNode("K").mat()
    xi = float(fs.getNode("xi").mat()[0, 0])
    D = fs.getNode("D").mat()
    size = (int(fs.getNode("image_width").real()), int(fs.getNode("image_height").real()))
    fs.release()
    return K, xi, D, size


def read_ocam(path):
    """The five blocks of numbers between the comment lines, as get_ocam_model reads them."""
    blocks = [
        [float(v) for v in line.split()]
        for line in Path(path).read_text().splitlines()
        if line.strip() and not line.lstrip().startswith("#")
    ]
    pol, invpol, centre, affine, size = blocks
    assert int(pol[0]) == len(pol) - 1 and int(invpol[0]) == len(invpol) - 1
    return {
        "pol": pol[1:],
        "invpol": invpol[1:],
        "xc": centre[0],
        "yc": centre[1],
        "c": affine[0],
        "d": affine[1],
        "e": affine[2],
        "height": int(size[0]),
        "width": int(size[1]),
    }


def world2cam(p, m):
    """OCamCalib's world2cam: the (row, col) of the 3D point p in the model's frame."""
    norm = math.sqrt(p[0] * p[0] + p[1] * p[1])
    if norm == 0:
        return m["xc"], m["yc"]
    theta = math.atan(p[2] / norm)
    rho, t_i = m["invpol"][0], 1.0
    for coefficient in m["invpol"][1:]:
        t_i *= theta
        rho += t_i * coefficient
    x, y = p[0] / norm * rho, p[1] / norm * rho
    return x * m["c"] + y * m["d"] + m["xc"], x * m["e"] + y + m["yc"]


def summary(errors):
    errors = sorted(errors)
    p99 = errors[max(0, math.ceil(0.99 * len(errors)) - 1)]  # nearest rank, as specchio's
    return f"mean {sum(errors) / len(errors):8.3f}  p99 {p99:8.3f}  max {errors[-1]:8.3f}"


def main():
    out = Path(sys.argv[1])
    points = json.loads((out / "check_points.json").read_text())["points"]
    K, xi, D, size = read_opencv(out / "opencv_omnidir.yaml")
    ocam = read_ocam(out / "ocamcalib_calib_results.txt")
    failures = []

    # 1. OpenCV's projection of the points our model could project.
    seen = [p for p in points if p["omnidir_pixel"] is not None]
    obj = np.array([p["omnidir_point"] for p in seen], dtype=np.float64).reshape(-1, 1, 3)
    projected, _ = cv2.omnidir.projectPoints(obj, np.zeros(3), np.zeros(3), K, xi, D)
    projected = projected.reshape(-1, 2)
    ours = np.array([p["omnidir_pixel"] for p in seen])
    worst = float(np.max(np.linalg.norm(projected - ours, axis=1)))
    print(f"OpenCV omnidir ({cv2.__version__}), {len(seen)} points: largest difference from ours {worst:.3g} px")
    if not worst <= OPENCV_TOLERANCE_PX:
        failures.append(f"omnidir: OpenCV and specchio differ by {worst} px")

    # 2. The OCamCalib port.
    ported = np.array([world2cam(p["ocamcalib_point"], ocam) for p in points])
    ours_oc = np.array([p["ocamcalib_row_col"] for p in points])
    worst_oc = float(np.max(np.linalg.norm(ported - ours_oc, axis=1)))
    print(f"OCamCalib world2cam (port), {len(points)} points: largest difference from ours {worst_oc:.3g} px")
    if not worst_oc <= OPENCV_TOLERANCE_PX:
        failures.append(f"ocamcalib: the port and specchio differ by {worst_oc} px")

    # 3. Against the pixels the points really lie on, per distance.
    print("error against the true pixel (px), per distance from the mirror:")
    for distance in sorted({p["distance_m"] for p in points}):
        cv_err = [
            float(np.hypot(*(q - np.array(p["pixel"]))))
            for p, q in zip(seen, projected)
            if p["distance_m"] == distance
        ]
        oc_err = [
            math.hypot(r - p["pixel"][1], c - p["pixel"][0])
            for p, (r, c) in zip(points, ported)
            if p["distance_m"] == distance
        ]
        print(f"  {distance:7.1f} m  omnidir {summary(cv_err)}   ocamcalib {summary(oc_err)}")

    for f in failures:
        print("FAIL:", f)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
