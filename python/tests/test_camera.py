"""The camera image of a scene's [sensor.imaging] from Python: a `camera` layer of codes
beside the clean `sensor` one, its noise what the camera model says (checked here from the
model's definition, on pixels whose light is known), and new noise each frame."""

from __future__ import annotations

import re

import numpy as np
import pytest

import specchio
from conftest import SCENES

CAMERA = """
[sensor.imaging]
exposure_s = 0.005
vignetting = 0
seed = 3
"""


def camera_scene(tmp_path) -> specchio.Scene:
    text = (SCENES / "test" / "six-colour-room.toml").read_text()
    path = tmp_path / "camera-room.toml"
    path.write_text(text + CAMERA)
    return specchio.Scene(path)


def test_the_camera_layer_is_the_models_noise_on_known_light(tmp_path):
    with specchio.Renderer(camera_scene(tmp_path)) as r:
        first, second = r.render(), r.render()
        batch = r.render_batch(np.array([[0.0, 0.0, 0.0, 0.0]]), out={"camera": np.zeros((1, 512, 512, 3), np.uint16)})
    camera = first["camera"]
    assert camera.shape == (512, 512, 3) and camera.dtype == np.uint16
    assert camera.max() <= 4095
    # The same pose twice: the same clean image, new noise.
    np.testing.assert_array_equal(first["sensor"], second["sensor"])
    assert (first["camera"] != second["camera"]).mean() > 0.5
    assert batch["camera"].any()
    # Off the mirror the sensor camera sees the green ceiling of an unlit room: linear
    # (0, 1, 0) exactly. Its green codes are the photon transfer curve's at one level:
    # mean b + K (Φt + Dt), variance K² (Φt + Dt + σr²) + 1/12 (EMVA 1288's linear model, the
    # datasheet camera's numbers, b the black level); red and blue see only the dark current
    # and the read noise, about the black level.
    ceiling = ~first["mask"] & (first["sensor"][..., 1] == 1.0) & (first["sensor"][..., 0] == 0.0)
    assert ceiling.sum() > 50_000
    full_well, read_noise, dark, black = 32359.0, 7.24, 1.5, 4.0
    k = 4095.0 / full_well
    charge = 3.0e6 * 0.005 + dark * 0.005
    green = camera[..., 1][ceiling].astype(np.float64)
    n = green.size
    mean, var = black + k * charge, k * k * (charge + read_noise**2) + 1.0 / 12.0
    assert abs(green.mean() - mean) < 5.0 * np.sqrt(var / n), (green.mean(), mean)
    assert abs(green.var(ddof=1) - var) < 5.0 * var * np.sqrt(2.0 / n), (green.var(ddof=1), var)
    red = camera[..., 0][ceiling].astype(np.float64)
    dark_mean = black + k * dark * 0.005
    dark_var = k * k * (dark * 0.005 + read_noise**2) + 1.0 / 12.0
    assert abs(red.mean() - dark_mean) < 5.0 * np.sqrt(dark_var / n), (red.mean(), dark_mean)


def test_a_scene_without_imaging_has_no_camera_layer(renderer):
    assert "camera" not in renderer.render()


def test_the_dataset_frames_blur_along_the_trajectory_as_the_command_does(tmp_path):
    """DatasetFrames (what each Ray worker runs) moves the robot along the trajectory during
    the exposure, as `specchio dataset` does: the same camera images, byte for byte."""
    from conftest import cli

    text = (SCENES / "test" / "six-colour-room.toml").read_text()
    blurred = "\n[sensor.imaging]\nexposure_s = 0.1\nmotion_blur_samples = 4\n"
    (tmp_path / "turning.toml").write_text(text + blurred)
    (tmp_path / "turn.csv").write_text("time,x,y,z,heading\n0,0,0,0,0\n0.5,0,0,0,45\n1,0,0,0,90\n")
    args = ["--trajectory", "turn.csv", "--out", "cli", "--outputs", "camera"]
    run = cli("dataset", "turning.toml", *args, cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    frames = specchio.DatasetFrames(tmp_path / "turning.toml", tmp_path / "turn.csv", encoders=0, outputs="camera")
    files = dict(frames.frames([1])[0][0])
    want = (tmp_path / "cli" / "frames" / "000001" / "sensor.camera.png").read_bytes()
    assert files["frames/000001/sensor.camera.png"] == want


def test_a_camera_given_in_python_is_the_scene_files(tmp_path):
    """`Scene(path, imaging={...})` states the camera as `[sensor.imaging]` would: the same
    camera image, code for code, as the file with that table; its mistakes are refused naming
    `imaging` and the key."""
    plain = SCENES / "test" / "six-colour-room.toml"
    given = specchio.Scene(plain, imaging={"exposure_s": 0.005, "vignetting": 0, "seed": 3})
    with specchio.Renderer(given) as r:
        ours = r.render()
    with specchio.Renderer(camera_scene(tmp_path)) as r:
        theirs = r.render()
    np.testing.assert_array_equal(ours["camera"], theirs["camera"])
    with specchio.Renderer(specchio.Scene(plain, imaging={})) as r:
        assert r.render()["camera"].dtype == np.uint16, "{} is the datasheet camera"
    # numpy's scalars as Python's numbers.
    with specchio.Renderer(specchio.Scene(plain, imaging={"exposure_s": np.float64(0.005), "vignetting": np.int64(0),
                                                          "seed": np.uint8(3)})) as r:
        np.testing.assert_array_equal(r.render()["camera"], theirs["camera"])
    for bad, says in [({"exposure_s": 20}, "imaging: exposure_s: must be"),
                      ({"exposur": 1}, "unknown field `exposur`"),
                      ({"exposure_s": float("nan")}, "imaging: exposure_s: must be a finite number, got nan"),
                      ({"exposure_s": None}, "imaging: exposure_s: None is not a number"),
                      # Its size, not its 301 digits.
                      ({"bit_depth": 10**300},
                       "imaging: bit_depth: an int of 997 bits is beyond a 64-bit integer")]:
        with pytest.raises(specchio.SpecchioError, match=re.escape(says)):
            specchio.Scene(plain, imaging=bad)
