"""specchio.dataset's `outputs`: the layers chosen, in one process and on Ray, the same files
as `specchio dataset --outputs`, byte for byte; a bad choice refused before anything is
written."""

from __future__ import annotations

import json

import pytest

import specchio
from conftest import ROBOT_CSV, cli, scene_path, tree


def test_chosen_layers_from_python_and_ray_are_the_commands(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "robot.csv").write_text(ROBOT_CSV)
    scene = str(scene_path("thesis-room"))
    run = cli("dataset", scene, "--trajectory", "robot.csv", "--out", "cli", "--outputs", "range,ids", cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    want = tree(tmp_path / "cli")
    names = {p.split("/")[-1] for p in want if p.startswith("frames/")}
    assert names == {"camera.json", "pose.json", "sensor.range.exr", "sensor.id.exr", "sensor.id.json"}
    record = specchio.dataset(scene, "robot.csv", "py", outputs=["range", "ids"])
    assert record["outputs"] == ["range", "ids"]
    assert tree(tmp_path / "py") == want
    specchio.dataset(
        scene, "robot.csv", "ray", outputs="range,ids", ray=True, workers=1, shard_size=3,
        worker_env={"LP_NUM_THREADS": "1"},
    )
    assert tree(tmp_path / "ray") == want
    assert json.loads(want["dataset.json"])["frame_files"] == [
        "camera.json", "sensor.range.exr", "sensor.id.exr", "sensor.id.json", "pose.json"
    ]


def test_a_bad_choice_writes_nothing_and_says_why(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "robot.csv").write_text(ROBOT_CSV)
    scene = str(scene_path("thesis-room"))
    cases = [
        (["image", "depth"], "outputs: `depth` is not a layer"),
        ("camera", "outputs: camera needs a camera model"),
        (3, r'^outputs: 3 \(an int\); give a str \("image,range"\) or a list of names'),
        # A list's wrong element is named by its place; `all` stands alone.
        (["image", None], r"^outputs\[1\]: None \(a NoneType\); give a name \(a str\)"),
        ("all,image", r"^outputs: `all` stands alone, not among layer names"),
    ]
    for outputs, says in cases:
        with pytest.raises(specchio.SpecchioError, match=says):
            specchio.dataset(scene, "robot.csv", "bad", outputs=outputs)
        assert not (tmp_path / "bad").exists()


def test_geometry_frame_from_python_and_ray_is_the_commands(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "robot.csv").write_text(ROBOT_CSV)
    scene = str(scene_path("thesis-room"))
    args = ("--outputs", "rays,points", "--geometry-frame", "base_link")
    run = cli("dataset", scene, "--trajectory", "robot.csv", "--out", "cli", *args, cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    want = tree(tmp_path / "cli")
    assert b"comment frame: ROS REP-103 base_link" in want["frames/000002/points.ply"]
    record = specchio.dataset(scene, "robot.csv", "py", outputs="rays,points", geometry_frame="base_link")
    assert record["geometry_frame"] == "base_link"
    assert tree(tmp_path / "py") == want
    specchio.dataset(
        scene, "robot.csv", "ray", outputs="rays,points", geometry_frame="base_link", ray=True,
        workers=1, shard_size=3, worker_env={"LP_NUM_THREADS": "1"},
    )
    assert tree(tmp_path / "ray") == want
    with pytest.raises(specchio.SpecchioError, match="geometry_frame: `world` is not a geometry frame"):
        specchio.dataset(scene, "robot.csv", "bad", geometry_frame="world")
    assert not (tmp_path / "bad").exists()
