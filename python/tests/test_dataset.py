"""specchio.dataset: in one process and on Ray, the same files as `specchio dataset`, byte
for byte; all or nothing."""

from __future__ import annotations

import json
import os
import pathlib
import signal
import subprocess

import numpy as np
import pytest

import specchio
from conftest import ROBOT_CSV, cli, scene_path, tree


@pytest.fixture(scope="module")
def made(tmp_path_factory):
    """The command's dataset of the thesis room along ROBOT_CSV, and the folder it ran in."""
    work = tmp_path_factory.mktemp("dataset")
    (work / "robot.csv").write_text(ROBOT_CSV)
    scene = str(scene_path("thesis-room"))
    run = cli("dataset", scene, "--trajectory", "robot.csv", "--out", "cli", cwd=work)
    assert run.returncode == 0, run.stderr
    return work, scene


def test_python_writes_what_the_command_writes(made, monkeypatch):
    work, scene = made
    monkeypatch.chdir(work)
    seen = []
    record = specchio.dataset(scene, "robot.csv", "py", progress=lambda d, n: seen.append((d, n)))
    # Once per frame written, in order, the last once the folder is placed.
    assert seen == [(d, 5) for d in range(1, 6)]
    want = tree(work / "cli")
    assert len(want) >= 5 * 9 + 2
    assert tree(work / "py") == want
    assert json.loads((work / "py" / "dataset.json").read_text()) == record
    assert record["frames"] == 5


def test_without_a_progress_callback_it_says_its_estimate(made):
    """A long dataset is not silent in Python either: without `progress=` it says on stderr
    what `specchio dataset` says (here at once, as the tests ask)."""
    import sys
    work, scene = made
    script = "import sys, specchio; specchio.dataset(sys.argv[1], 'robot.csv', 'said')"
    env = {**os.environ, "SPECCHIO_ESTIMATE_AFTER_S": "0"}
    run = subprocess.run([sys.executable, "-c", script, scene], cwd=work, env=env,
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    lines = [l for l in run.stderr.splitlines() if l.startswith("dataset said: ")]
    assert lines and " of 5 frames in " in lines[0] and " left" in lines[0], run.stderr
    assert tree(work / "said") == tree(work / "cli")


def test_the_world_frame_is_asked_for_alike_in_python_and_the_command(made, monkeypatch):
    """Panoramas are in the robot's frame unless the scene's is asked for; only they and
    their records differ, and Python asks for it as the command does."""
    work, scene = made
    monkeypatch.chdir(work)
    args = ["--trajectory", "robot.csv", "--out", "cli-world", "--panorama-frame", "world"]
    run = cli("dataset", scene, *args, cwd=work)
    assert run.returncode == 0, run.stderr
    robot, world = tree(work / "cli"), tree(work / "cli-world")
    assert json.loads(robot["dataset.json"])["panorama_frame"] == "robot"
    assert json.loads(world["dataset.json"])["panorama_frame"] == "world"
    assert sorted(robot) == sorted(world)
    differing = {p for p in robot if robot[p] != world[p]}
    # Frame 0 faces +X (heading 0): both frames put its seam there.
    assert not any(p.startswith("frames/000000/") for p in differing)
    assert any(p.startswith("frames/000001/sensor.panorama.") for p in differing)
    expected = ("sensor.panorama.", "camera.json", "dataset.json")
    assert all(any(e in p for e in expected) for p in differing), sorted(differing)
    record = specchio.dataset(scene, "robot.csv", "py-world", panorama_frame="world")
    assert record["panorama_frame"] == "world"
    assert tree(work / "py-world") == world
    frames = specchio.DatasetFrames(scene, "robot.csv", encoders=0, panorama_frame="world")
    got = {path: data for files, _ in frames.frames([2]) for path, data in files}
    assert got and all(got[p] == world[p] for p in got)
    with pytest.raises(specchio.SpecchioError, match="panorama_frame: `sky` is not a panorama frame: robot or world"):
        specchio.dataset(scene, "robot.csv", "bad", panorama_frame="sky")
    assert not (work / "bad").exists()


def test_a_workers_frames_are_the_same_with_any_number_of_encoders(made, monkeypatch):
    work, scene = made
    monkeypatch.chdir(work)
    want = tree(work / "cli")
    for encoders in [0, 1, 3]:
        frames = specchio.DatasetFrames(scene, "robot.csv", encoders=encoders)
        got = {path: data for files, _ in frames.frames([4, 0, 2]) for path, data in files}
        asked = tuple(f"frames/{n:06d}/" for n in [4, 0, 2])
        assert sorted(got) == sorted(p for p in want if p.startswith(asked))
        assert all(got[p] == want[p] for p in got), encoders
    with pytest.raises(specchio.SpecchioError, match="encoders: 17; must be a whole number from 0 to 16"):
        specchio.DatasetFrames(scene, "robot.csv", encoders=17)


def test_ray_with_two_workers_writes_the_same_bytes(made, monkeypatch):
    work, scene = made
    monkeypatch.chdir(work)
    seen = []
    record = specchio.dataset(
        scene,
        "robot.csv",
        "ray",
        ray=True,
        workers=2,
        shard_size=2,
        worker_env={"LP_NUM_THREADS": "1"},
        progress=lambda d, n: seen.append(d),
    )
    assert seen[-1] == 5 and len(seen) == 3  # shards of 2, 2 and 1 poses
    assert tree(work / "ray") == tree(work / "cli")
    assert record["frames"] == 5


def ours(pid: int) -> bool:
    """Whether process `pid` descends from this one (a worker of our local Ray, not another
    run's on the same machine)."""
    for _ in range(8):
        try:
            stat = pathlib.Path(f"/proc/{pid}/stat").read_text()
        except OSError:
            return False
        pid = int(stat.rsplit(")", 1)[1].split()[1])
        if pid == os.getpid():
            return True
        if pid <= 1:
            return False
    return False


def test_a_killed_worker_is_restarted_and_its_shard_retried(made, monkeypatch):
    work, scene = made
    monkeypatch.chdir(work)
    killed = []

    def kill_a_worker(done, total):
        # After the first shard, while the other worker renders: SIGKILL one worker process.
        if killed:
            return
        workers = our_workers()
        assert workers, "no worker process to kill"
        os.kill(workers[0], signal.SIGKILL)
        killed.append(workers[0])

    specchio.dataset(scene, "robot.csv", "killed", ray=True, workers=2, shard_size=1, progress=kill_a_worker)
    assert killed
    assert tree(work / "killed") == tree(work / "cli")


def our_workers() -> list[int]:
    """The pids of this run's Ray worker actors."""
    ps = subprocess.run(["pgrep", "-af", "ray::"], capture_output=True, text=True)
    return [
        int(line.split()[0])
        for line in ps.stdout.splitlines()
        if line.split(None, 1)[1].startswith("ray::_Worker") and ours(int(line.split()[0]))
    ]


def test_a_worker_dead_past_its_restarts_leaves_no_staged_frames(made, monkeypatch):
    """A worker killed more often than Ray restarts it ends the run with Ray's ActorDiedError,
    and the frames staged so far are gone at once, while the exception (which holds the run's
    output in its traceback, as a notebook keeps it) is still alive."""
    import ray

    work, scene = made
    monkeypatch.chdir(work)
    killed = []

    def kill_the_worker(done, total):
        # After each shard while kills remain: one more death than Ray restarts.
        if len(killed) > specchio.ray.RETRIES:
            return
        workers = our_workers()
        assert workers, "no worker process to kill"
        os.kill(workers[0], signal.SIGKILL)
        killed.append(workers[0])

    with pytest.raises(ray.exceptions.ActorDiedError) as info:
        specchio.dataset(scene, "robot.csv", "died", ray=True, workers=1, shard_size=1, progress=kill_the_worker)
    assert info.traceback
    assert len(killed) == specchio.ray.RETRIES + 1
    assert not [p.name for p in work.iterdir() if "died" in p.name]


def test_a_bad_trajectory_writes_nothing_and_names_line_and_field(made, monkeypatch):
    work, scene = made
    monkeypatch.chdir(work)
    (work / "bad.csv").write_text("time,x,y,z,heading\n0,0,3,0,0\n1,9,3,0,0\n")
    for ray in (False, True):
        with pytest.raises(specchio.SpecchioError, match=r"bad.csv:3: position: the mirror"):
            specchio.dataset(scene, "bad.csv", "bad", ray=ray)
        assert not (work / "bad").exists()
    with pytest.raises(specchio.SpecchioError, match="no-such-device"):
        specchio.dataset(scene, "robot.csv", "bad", ray=True, workers=1, device="no-such-device")
    with pytest.raises(specchio.SpecchioError, match="shard_size"):
        specchio.dataset(scene, "robot.csv", "bad", ray=True, shard_size=0)
    with pytest.raises(specchio.SpecchioError, match="ray=True"):
        specchio.dataset(scene, "robot.csv", "bad", workers=2)
    assert not (work / "bad").exists()


def test_an_interrupted_run_writes_nothing(made, monkeypatch):
    work, scene = made
    monkeypatch.chdir(work)

    def stop(done, total):
        if done == 2:
            raise KeyboardInterrupt

    for on_ray in ({}, {"ray": True, "workers": 1, "shard_size": 1}):
        # The exception (`info`) is kept, as a notebook keeps the last one: its traceback
        # holds the run's output, whose staged files must be gone anyway.
        with pytest.raises(KeyboardInterrupt) as info:
            specchio.dataset(scene, "robot.csv", "stopped", progress=stop, **on_ray)
        assert info.traceback
        assert not (work / "stopped").exists()
        assert not [p for p in work.iterdir() if "stopped" in p.name], on_ray


# A whole frame of a run of the default layers (every layer but the ray map and the point
# cloud; the thesis room has no camera model): a panorama among its files, as the panoramas
# layer asks.
FILES = [
    "sensor.exr", "sensor.png", "sensor.range.exr", "sensor.id.exr", "sensor.id.json",
    "camera.json", "pose.json", "sensor.panorama.lonlat.png",
]


def test_the_output_takes_only_its_frames_files(made, monkeypatch):
    work, scene = made
    monkeypatch.chdir(work)
    out = specchio.DatasetOutput(scene, "robot.csv", "parts")
    line = lambda n: json.dumps({"folder": f"frames/{n:06d}", "frame": n})
    frame = lambda n: [(f"frames/{n:06d}/{name}", b"x") for name in FILES]
    cli = work / "cli"
    made_with = json.loads((cli / "dataset.json").read_text())
    run = (made_with["lookup"], made_with["ground_truth"])
    # Bound to a run first: its lookup is what every frame must have been made by.
    with pytest.raises(specchio.SpecchioError, match=r"place\(\) comes after begin\(\)"):
        out.place(frame(0), line(0))
    with pytest.raises(specchio.SpecchioError, match=r"finish\(\) comes after begin\(\)"):
        out.finish(*run)
    assert out.begin(*run, "lavapipe") == [0, 1, 2, 3, 4]
    for path in ["../escape.txt", "frames/000009/x.exr", "frames/000001/../../x", "/abs", "index.jsonl"]:
        with pytest.raises(specchio.SpecchioError, match="frame folders"):
            out.place([(path, b"x")], line(0))
    with pytest.raises(specchio.SpecchioError, match="frame 0: no sensor.exr"):
        out.place(frame(0)[1:], line(0))
    no_panorama = [(p, b) for p, b in frame(0) if "panorama" not in p]
    with pytest.raises(specchio.SpecchioError, match=r"frame 0: no sensor\.panorama\.\*"):
        out.place(no_panorama, line(0))
    with pytest.raises(specchio.SpecchioError, match="frame 0: pose.json twice"):
        out.place(frame(0) + [("frames/000000/pose.json", b"y")], line(0))
    with pytest.raises(specchio.SpecchioError, match="frames 0 and 1 in one call"):
        out.place(frame(0) + frame(1), line(0))
    with pytest.raises(specchio.SpecchioError, match="index line 0: not frame 0's line"):
        out.place(frame(0), line(1))
    with pytest.raises(specchio.SpecchioError, match="index line 0"):
        out.place(frame(0), line(0) + "\n" + line(1))
    # The right names are not enough: a frame must be this dataset's.
    with pytest.raises(specchio.SpecchioError, match="frame 0: its index line is not the one"):
        out.place(frame(0), line(0))
    index = (cli / "index.jsonl").read_text().splitlines()
    real = lambda n: [(str(p.relative_to(cli)), p.read_bytes()) for p in sorted((cli / f"frames/{n:06d}").iterdir())]
    # A ray map in another frame: only a run that writes one can tell (the default does not).
    every = specchio.DatasetOutput(scene, "robot.csv", "parts-all", outputs="all")
    every.begin(*run, "lavapipe")
    based = specchio.DatasetFrames(scene, "robot.csv", encoders=0, geometry_frame="base_link", outputs="all")
    ((files, line1),) = based.frames([1])
    with pytest.raises(specchio.SpecchioError, match="frame 1: its ray map is not in the dataset's scene frame"):
        every.place(files, line1)
    del every
    assert not (work / "parts-all").exists()
    world = specchio.DatasetFrames(scene, "robot.csv", encoders=0, panorama_frame="world")
    # Indices and files of the wrong kind are named by their place, not by PyO3's TypeError.
    for indices, says in [
        ([-1], r"^indices\[0\]: -1; must be a frame index from 0 to 4"),
        ([0, 2**70], r"^indices\[1\]: an int of 71 bits; must be a frame index"),
        ([True], r"^indices\[0\]: True \(a bool\); must be a frame index"),
        (0, r"^indices: 0 \(an int\); give a list of frame indices"),
    ]:
        with pytest.raises(specchio.SpecchioError, match=says):
            world.frames(indices)
    for files, says in [
        ([("frames/000000/camera.json", "str")], r"^files\[0\]\[1\]: 'str' \(a str\); give the file's bytes"),
        ([("frames/000000/camera.json",)], r"^files\[0\]: .*give a \(path, bytes\) pair"),
        ("frames", r"^files: 'frames' \(a str\); give a list of \(path, bytes\) pairs"),
    ]:
        with pytest.raises(specchio.SpecchioError, match=says):
            out.place(files, line(0))
    ((files, line1),) = world.frames([1])
    with pytest.raises(specchio.SpecchioError, match="frame 1: its panoramas are not in the dataset's robot frame"):
        out.place(files, line1)
    # A frame of this dataset made by another lookup: its colour and labels are not the run's.
    other = "plain" if run[0] != "plain" else "box"
    boxed = specchio.DatasetFrames(scene, "robot.csv", lookup=other, encoders=0)
    ((files, line1),) = boxed.frames([1])
    with pytest.raises(specchio.SpecchioError, match=f"frame 1: it was rendered with the {other} lookup and cube ground truth, not this run's {run[0]} and {run[1]}"):
        out.place(files, line1)
    out.place(real(0), index[0])
    with pytest.raises(specchio.SpecchioError, match="frame 0 was placed already"):
        out.place(real(0), index[0])
    # The summary names the run the frames were made by, nothing else.
    with pytest.raises(specchio.SpecchioError, match=f'lookup "{other}" and ground_truth "cube": the frames were made with "{run[0]}" and "{run[1]}"'):
        out.finish(other, "cube")
    with pytest.raises(specchio.SpecchioError, match="frame 1 was never placed"):
        out.finish(*run)
    for n in range(1, 5):
        out.place(real(n), index[n])
    out.close()
    with pytest.raises(specchio.SpecchioError, match="the dataset was already closed"):
        out.finish(*run)
    assert not (work / "parts").exists()


def test_a_stopped_run_goes_on_from_its_frames_on_ray_to_the_same_bytes(made, monkeypatch):
    work, scene = made
    monkeypatch.chdir(work)

    def stop(done, total):
        if done == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt) as stopped:
        specchio.dataset(scene, "robot.csv", "resumed", progress=stop, resume=True)
    assert not (work / "resumed").exists()
    # The note says what was kept and how to go on (Python 3.11+ has notes; Debian 12 has 3.11).
    notes = getattr(stopped.value, "__notes__", [])
    assert any("2 frame(s) are kept in" in n and "resumed.partial" in n for n in notes), notes
    journal = (work / "resumed.partial" / "journal.jsonl").read_text().splitlines()
    assert [json.loads(l)["frame"]["frame"] for l in journal[1:]] == [0, 1]
    # Another lookup is another dataset: refused, the kept frames left as they are.
    with pytest.raises(specchio.SpecchioError, match="resumed.partial was made by another run"):
        specchio.dataset(scene, "robot.csv", "resumed", lookup="plain", resume=True)
    assert len((work / "resumed.partial" / "journal.jsonl").read_text().splitlines()) == 3
    # Resumed by the other driver: Ray renders the three frames left.
    seen = []
    specchio.dataset(
        scene,
        "robot.csv",
        "resumed",
        resume=True,
        ray=True,
        workers=2,
        shard_size=1,
        worker_env={"LP_NUM_THREADS": "1"},
        progress=lambda d, n: seen.append(d),
    )
    assert seen == [3, 4, 5]
    assert tree(work / "resumed") == tree(work / "cli")
    assert not (work / "resumed.partial").exists()


def test_trajectories_read_as_python(made):
    work, _ = made
    poses = specchio.read_trajectory(work / "robot.csv")
    assert poses[1] == {"time": 0.5, "position": [1.0, 3.0, 0.5], "heading": 45.0}
    (work / "broken.csv").write_text("time,x,y,z,heading\n0,0,3,zero,0\n")
    with pytest.raises(specchio.SpecchioError, match=r"broken.csv:2: z: `zero` is not a number"):
        specchio.read_trajectory(work / "broken.csv")


def test_the_renderer_gives_the_dataset_frames_layers(made):
    """A batch at the trajectory's poses is the dataset, layer for layer (read back with
    specchio.read_exr): one far plane and one renderer set-up for both."""
    work, scene = made
    # The ray map, which the default leaves out.
    run = cli("dataset", scene, "--trajectory", "robot.csv", "--out", "cli-rays", "--outputs", "image,rays,range,ids", cwd=work)
    assert run.returncode == 0, run.stderr
    poses = specchio.read_trajectory(work / "robot.csv")
    array = np.array([[*p["position"], p["heading"]] for p in poses])
    with specchio.Renderer(specchio.Scene(scene)) as r:
        batch = r.render_batch(array, times=[p["time"] for p in poses])
    for i in range(len(poses)):
        folder = work / "cli-rays" / "frames" / f"{i:06d}"
        colour = specchio.read_exr(folder / "sensor.exr")
        assert np.array_equal(np.stack([colour[c] for c in "RGB"], -1), batch["sensor"][i])
        rays = specchio.read_exr(folder / "sensor.rays.exr")
        origin = np.stack([rays[f"origin.{c}"] for c in "XYZ"], -1)
        direction = np.stack([rays[f"direction.{c}"] for c in "XYZ"], -1)
        assert np.array_equal(origin, batch["ray_origin"][i])
        assert np.array_equal(direction, batch["ray_direction"][i])
        assert np.array_equal(rays["mask"] == 1.0, batch["mask"][i])
        assert np.array_equal(specchio.read_exr(folder / "sensor.range.exr")["range"], batch["range"][i])
        ids = specchio.read_exr(folder / "sensor.id.exr")["id"]
        assert ids.dtype == np.uint32 and np.array_equal(ids, batch["ids"][i])


def test_read_exr_refuses_what_is_not_an_exr(made):
    work, _ = made
    with pytest.raises(specchio.SpecchioError, match="robot.csv: not an OpenEXR image"):
        specchio.read_exr(work / "robot.csv")
    with pytest.raises(specchio.SpecchioError, match="nothing.exr"):
        specchio.read_exr(work / "nothing.exr")
    truncated = work / "truncated.exr"
    truncated.write_bytes((work / "cli" / "frames" / "000000" / "sensor.exr").read_bytes()[:5000])
    with pytest.raises(specchio.SpecchioError, match="truncated.exr"):
        specchio.read_exr(truncated)


def test_the_pose_grid_is_the_commands(tmp_path):
    scene = str(scene_path("thesis-room"))
    run = cli("dataset", scene, "--grid", "4", "--out", "grid", cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    lines = [json.loads(l) for l in (tmp_path / "grid" / "index.jsonl").read_text().splitlines()]
    want = np.array([[*l["scene"]["position_m"], l["scene"]["heading_deg"]] for l in lines])
    grid = specchio.pose_grid(specchio.Scene(scene), 4.0)
    assert grid.shape == (8, 4) and grid.dtype == np.float64
    assert np.array_equal(grid, want)
    turned = specchio.pose_grid(specchio.Scene(scene), 4.0, headings=4, time=0.0)
    assert turned.shape == (32, 4) and list(turned[:4, 3]) == [0.0, 90.0, 180.0, 270.0]
    # Out of range, however far: the range said is the grid's own (2**64 said 0..4294967295).
    for headings in (0, 361, 2**64, 2**200):
        with pytest.raises(specchio.SpecchioError, match=r"headings: .*from 1 to 360"):
            specchio.pose_grid(specchio.Scene(scene), 4.0, headings=headings)


def test_errors_name_the_arguments_python_was_given_not_the_commands_options(tmp_path):
    """The engine's messages are the command line's; from Python they say the argument (or
    the scene field) that sets the same thing, never an option the caller cannot give."""
    scene = str(scene_path("thesis-room"))
    cases = [
        (lambda: specchio.pose_grid(specchio.Scene(scene), 0.0), r"spacing: the spacing must be"),
        (lambda: specchio.pose_grid(specchio.Scene(scene), 4.0, time=-1.0), r"time: must be"),
        (lambda: specchio.dataset(scene, out=str(tmp_path / "a"), grid=0.0), r"grid: the spacing"),
        (
            lambda: specchio.dataset(scene, out=str(tmp_path / "b"), grid=4.0, time=1e300, format="mcap"),
            r"time: must be a finite number of seconds from 0 to 1e9",
        ),
        (lambda: specchio.Renderer(specchio.Scene(scene), device=""), r'device="" names no device'),
    ]
    for call, says in cases:
        with pytest.raises(specchio.SpecchioError, match=says) as raised:
            call()
        assert "--" not in str(raised.value), raised.value
    # A path is the user's, whatever it holds: only an option standing alone is said anew.
    folder = tmp_path / "--grid"
    folder.mkdir()
    (folder / "t.csv").write_text("time,x,y,z,heading\n0,0,1,0,zz\n")
    with pytest.raises(specchio.SpecchioError, match=r"--grid/t.csv:2: heading: `zz` is not a number"):
        specchio.dataset(scene, str(folder / "t.csv"), out=str(tmp_path / "c"))
    (tmp_path / "v.csv").write_text("time,x,y,z,heading\n0,0,1,0,--time\n")
    with pytest.raises(specchio.SpecchioError, match=r"v.csv:2: heading: `--time` is not a number"):
        specchio.dataset(scene, str(tmp_path / "v.csv"), out=str(tmp_path / "c"))



def test_a_grid_dataset_from_python_is_the_commands(tmp_path, monkeypatch):
    """`specchio.dataset(..., grid=)` in one process and on Ray: the folder `--grid` writes."""
    monkeypatch.chdir(tmp_path)
    scene = str(scene_path("thesis-room"))
    run = cli("dataset", scene, "--grid", "4", "--out", "cli", cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    record = specchio.dataset(scene, out="py", grid=4.0)
    assert record["trajectory"] == "grid: spacing 4 m, 1 heading(s), t = 0 s"
    specchio.dataset(scene, out="ray", grid=4.0, ray=True, workers=2, worker_env={"LP_NUM_THREADS": "1"})
    assert tree(tmp_path / "py") == tree(tmp_path / "cli")
    assert tree(tmp_path / "ray") == tree(tmp_path / "cli")
    for bad, message in [
        ({"out": "x"}, "give the poses"),
        ({"out": "x", "trajectory": "t.csv", "grid": 4.0}, "not both"),
        ({"out": "x", "trajectory": "t.csv", "headings": 2}, "a grid's"),
        ({"grid": 4.0}, "out: the dataset's folder is required"),
        ({"out": "x", "grid": 4.0, "headings": 0}, "headings: 0; must be a whole number from 1 to 360"),
        # Ray's own settings without Ray were ignored silently.
        ({"out": "x", "grid": 4.0, "shard_size": 0}, "shard_size are for ray=True"),
    ]:
        with pytest.raises(specchio.SpecchioError, match=message):
            specchio.dataset(scene, **bad)
    assert not (tmp_path / "x").exists()