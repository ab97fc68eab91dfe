"""specchio.reference (the exact CPU ray tracer) against the GPU renderer's traced labels,
and specchio.calibrate."""

from __future__ import annotations

import inspect
import json
import re
import os
import signal
import subprocess
import sys

import numpy as np
import pytest

import specchio
from conftest import cli, scene_path, tree


def test_the_traced_labels_match_the_exact_reference(thesis, renderer):
    if renderer.ground_truth != "traced":
        raise AssertionError(f"the default device gave no traced labels ({renderer.device})")
    pose = (0.8, 3.0, -0.4, 120.0)
    gpu = renderer.render(pose=pose, time=0.5)
    exact = specchio.reference(thesis, pose=pose, time=0.5)
    assert set(exact) == set(gpu)
    both = gpu["mask"] & exact["mask"]
    # The two masks are the same pixels but for the rim's sub-pixel edge.
    assert (gpu["mask"] != exact["mask"]).sum() <= 0.002 * both.sum()
    # Float32 on the GPU against float64 on the CPU: measured on lavapipe, origins agree to
    # 4.5e-7 m at p99 and 1.1e-5 m at worst, where the camera ray grazes the sphere's rim
    # (the hit is ill-conditioned there); directions to 8e-7 at p99, 1.8e-5 at worst.
    origin = np.abs(gpu["ray_origin"][both] - exact["ray_origin"][both]).max(axis=-1)
    direction = np.abs(gpu["ray_direction"][both] - exact["ray_direction"][both]).max(axis=-1)
    assert np.percentile(origin, 99) < 1e-6 and origin.max() < 5e-5
    assert np.percentile(direction, 99) < 2e-6 and direction.max() < 1e-4
    same = both & (gpu["ids"] == exact["ids"])
    # Ids differ only where a ray grazes an edge between two surfaces.
    assert same.sum() >= 0.998 * both.sum()
    np.testing.assert_allclose(gpu["range"][same], exact["range"][same], atol=2e-4)


def test_reference_errors_are_named(thesis):
    # Named, with the range, whatever the int (not an OverflowError naming nothing).
    for bad in (0, -1, 2**64, 4097):
        with pytest.raises(specchio.SpecchioError, match=rf"spp: {bad}; must be a whole number from 1 to 4096"):
            specchio.reference(thesis, spp=bad)
    # A bool is an int to Python, not a count here.
    with pytest.raises(specchio.SpecchioError, match=r"spp: True \(a bool\); must be a whole number"):
        specchio.reference(thesis, spp=True)
    # Beyond any fixed width (PyO3 alone raised a bare OverflowError), said by size.
    for bad, says in [(2**200, "an int of 201 bits"), (-(2**100), "a negative int of 101 bits")]:
        with pytest.raises(specchio.SpecchioError, match=rf"spp: {says}; must be a whole number from 1 to 4096"):
            specchio.reference(thesis, spp=bad)
    with pytest.raises(specchio.SpecchioError, match="pose: position"):
        specchio.reference(thesis, pose=(20.0, 3.0, 0.0, 0.0))
    # Named as the argument given: `pose`, not a batch's `poses[0]`.
    with pytest.raises(specchio.SpecchioError, match=r"^pose: position: every value"):
        specchio.reference(thesis, pose=(float("nan"), 3.0, 0.0, 0.0))
    with pytest.raises(specchio.SpecchioError, match=r"^pose: heading"):
        specchio.reference(thesis, pose=(0.0, 3.0, 0.0, float("inf")))


def test_calibrate_writes_what_the_command_writes(tmp_path):
    scene = str(scene_path("hyperbolic-room"))
    record = specchio.calibrate(specchio.Scene(scene), tmp_path / "py")
    run = cli("calibrate", scene, "--out", str(tmp_path / "cli"), cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    assert tree(tmp_path / "py") == tree(tmp_path / "cli")
    assert json.loads((tmp_path / "py" / "calibration.json").read_text()) == record
    # The hyperboloid is central: the unified model fits it to a small fraction of a degree.
    assert record["omnidir"]["residual_deg"]["p99"] < 0.05


def test_the_calibrations_ros_frames_are_the_datasets(tmp_path):
    """The hyperbolic room's omnidir TF frame (calibration.json `ros`) is the camera's optical
    frame of the dataset's pose.json moved to the viewpoint, where base_link is."""
    scene = specchio.Scene(scene_path("hyperbolic-room"))
    cal = specchio.calibrate(scene, tmp_path / "cal")["ros"]
    x, y, z = scene.mirror_position
    (tmp_path / "t.csv").write_text(f"time,x,y,z,heading\n0,{x!r},{y!r},{z!r},0\n")
    specchio.dataset(scene.path, tmp_path / "t.csv", tmp_path / "ds")
    pose = json.loads((tmp_path / "ds" / "frames" / "000000" / "pose.json").read_text())["ros"]
    np.testing.assert_allclose(cal["viewpoint_m"], pose["base_link_position_m"], atol=1e-6)
    q_cal = np.array(cal["omnidir"]["quaternion_xyzw"])
    q_camera = np.array(pose["camera_optical_quaternion_xyzw"])
    assert min(np.linalg.norm(q_cal - q_camera), np.linalg.norm(q_cal + q_camera)) < 1e-6
    # The TF frames are rotations: their rows orthonormal with determinant +1.
    for model in ("omnidir", "ocamcalib"):
        rows = np.array(cal[model]["rows"])
        np.testing.assert_allclose(rows @ rows.T, np.eye(3), atol=1e-12)
        assert abs(np.linalg.det(rows) - 1.0) < 1e-12


def test_parameters_show_their_defaults():
    # They take any value (to refuse 2**200 or "0" by name), and help() still shows the
    # defaults: no `...` where a default is.
    assert inspect.signature(specchio.reference).parameters["spp"].default == 1
    assert inspect.signature(specchio.pose_grid).parameters["headings"].default == 1
    assert inspect.signature(specchio.Descriptor).parameters["k"].default == 8
    from specchio import _specchio

    for call in [
        specchio.reference,
        specchio.pose_grid,
        specchio.calibrate,
        specchio.Descriptor,
        specchio.Renderer,
        specchio.Renderer.render,
        _specchio.dataset,
        specchio.DatasetFrames,
        specchio.DatasetOutput,
    ]:
        shown = inspect.signature(call)
        assert all(p.default is not Ellipsis for p in shown.parameters.values()), (call, shown)
    assert inspect.signature(specchio.calibrate).parameters["time"].default == 0.0
    assert inspect.signature(specchio.Renderer).parameters["validate"].default is False
    assert inspect.signature(specchio.DatasetOutput).parameters["panorama_frame"].default == "robot"


def _interrupted_after_estimate(call: str, args: list[str], estimate: str) -> tuple[int, list[str]]:
    """Runs `specchio.<call>(*sys.argv[1:])` in a Python of its own, its estimate said after
    the first part (the delay is read once a process), and sends it Ctrl-C once a stderr line
    starts with `estimate`: its exit status (42 for KeyboardInterrupt, whose notes it writes
    to stderr) and its stderr lines."""
    # Python's own Ctrl-C handler, whatever the child inherited: a job started in the
    # background of a script ignores SIGINT, and Python then keeps ignoring it.
    script = (
        "import signal, sys, specchio\n"
        "signal.signal(signal.SIGINT, signal.default_int_handler)\n"
        "try:\n"
        f"    specchio.{call}\n"
        "except KeyboardInterrupt as stopped:\n"
        "    print(*getattr(stopped, '__notes__', []), sep='\\n', file=sys.stderr)\n"
        "    sys.exit(42)\n"
    )
    child = subprocess.Popen([sys.executable, "-c", script, *args], stderr=subprocess.PIPE,
                             text=True, env={**os.environ, "SPECCHIO_ESTIMATE_AFTER_S": "0"})
    said = []
    for line in child.stderr:
        said.append(line)
        if line.startswith(estimate):
            child.send_signal(signal.SIGINT)
            break
    said.extend(child.stderr)
    return child.wait(timeout=300), said


def test_a_large_calibration_says_its_estimate_and_stops_at_ctrl_c(tmp_path):
    """The largest sensor a calibration takes (4096², seconds of work) says its estimate on
    stderr as the command does, and Ctrl-C, sent once it has, stops it between parts:
    KeyboardInterrupt, nothing written."""
    text = (scene_path("test/six-colour-room")).read_text()
    path = tmp_path / "large.toml"
    path.write_text(text.replace("[sensor]\n", "[sensor]\nresolution = [4096, 4096]\n"))
    status, said = _interrupted_after_estimate(
        "calibrate(specchio.Scene(sys.argv[1]), sys.argv[2])",
        [str(path), str(tmp_path / "stopped")], "calibrate: sensor 4096x4096: ")
    assert status == 42, "".join(said)
    assert any("10 % done in " in line for line in said), said
    assert not (tmp_path / "stopped").exists()
    assert not [p for p in tmp_path.iterdir() if "stopped" in p.name]


def test_a_bags_model_fit_says_its_estimate_and_stops_at_ctrl_c(tmp_path):
    """A dataset with a ROS 2 bag of a central mirror fits the unified model before its first
    frame (seconds at 4096²): it says its estimate, and Ctrl-C there raises KeyboardInterrupt
    with nothing written, as `calibrate` does."""
    for shared in ("textures", "meshes"):
        (tmp_path / shared).symlink_to(scene_path("hyperbolic-room").parent / shared)
    text = scene_path("hyperbolic-room").read_text()
    path = tmp_path / "large.toml"
    path.write_text(text.replace("resolution = [512, 512]", "resolution = [4096, 4096]", 1))
    assert specchio.Scene(path).sensor_size == (4096, 4096)
    x, y, z = specchio.Scene(path).mirror_position
    (tmp_path / "t.csv").write_text(f"time,x,y,z,heading\n0,{x!r},{y!r},{z!r},0\n")
    status, said = _interrupted_after_estimate(
        "dataset(sys.argv[1], sys.argv[2], sys.argv[3], format='mcap')",
        [str(path), str(tmp_path / "t.csv"), str(tmp_path / "stopped")],
        "dataset: the bag's unified model: sensor 4096x4096: ")
    assert status == 42, "".join(said)
    assert any("15 % done in " in line for line in said), said
    assert not (tmp_path / "stopped").exists()
    assert not [p for p in tmp_path.iterdir() if "stopped" in p.name]


def test_a_long_reference_says_its_estimate_and_stops_at_ctrl_c(tmp_path):
    """A reference whose sensor's exposure spans 1,024 instants (a rolling shutter and motion
    blur: an exact trace at each, minutes of work) says the whole of it, exposure included,
    before the bulk, and Ctrl-C stops it within a pixel: KeyboardInterrupt, its note saying
    where it stopped, as the command says. It used to trace on, silent, for five minutes and
    only then see the Ctrl-C."""
    text = (scene_path("test/six-colour-room")).read_text()
    path = tmp_path / "blurred.toml"
    path.write_text(text.replace("[sensor]\n", "[sensor]\nresolution = [256, 256]\n")
                    + "\n[sensor.imaging]\nexposure_s = 0.001\nrolling_shutter_s = 0.015\n"
                    "motion_blur_samples = 64\n")
    estimate = "reference: observer "
    status, said = _interrupted_after_estimate(
        "reference(specchio.Scene(sys.argv[1]))", [str(path)], estimate)
    assert status == 42, "".join(said)
    line = next(line for line in said if line.startswith(estimate))
    assert "sensor 256x256 cameras at 1 spp, and the sensor's exposure at 1024 instants: " in line
    # The observer's pixels, the sensor's, and the sensor's again at each instant.
    observer = specchio.Scene(path).observer_size
    total = observer[0] * observer[1] + 256 * 256 * 1025
    assert f" of {total} pixels in " in line, line
    # Where it stopped: within a camera's rows or the exposure's instants, not at the end.
    stopped = [line for line in said if line.startswith("specchio.reference stopped after ")]
    assert stopped and ("rows of the " in stopped[0] or " instants" in stopped[0]), said


def test_one_pose_is_refused_as_a_batchs_would_be(thesis, renderer):
    """`pose=` takes what `render_batch`'s rows take: bools, complex numbers and other shapes
    are refused naming `pose` (a complex pose rendered before, its imaginary part dropped
    with only numpy's warning)."""
    for bad, says in [(np.zeros(4, complex), "pose: not an array of numbers (dtype complex128)"),
                      (np.array([True, False, False, True]), "pose: not an array of numbers (dtype bool)"),
                      (np.zeros((4, 1)), "pose: an array of shape [4, 1]"),
                      (np.array(0.0), "pose: an array of shape []"),
                      ((0, 3, 0), "pose: an array of shape [3]")]:
        with pytest.raises(specchio.SpecchioError, match=re.escape(says)):
            renderer.render(pose=bad)
        with pytest.raises(specchio.SpecchioError, match=re.escape(says)):
            specchio.reference(thesis, pose=bad)
    x, y, z = thesis.mirror_position
    frame = renderer.render(pose=np.array([x, y, z, 0], dtype=np.float32))
    assert frame["mask"].any()
