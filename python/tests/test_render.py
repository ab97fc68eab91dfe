"""specchio.Renderer: a frame and a batch as numpy arrays, the caller's buffers, and errors
that name what is wrong."""

from __future__ import annotations

import subprocess
import sys
import warnings

import numpy as np
import pytest

import specchio
from conftest import scene_path, usable_devices

SHAPES = {
    "sensor": ((512, 512, 3), np.float32),
    "observer": ((600, 800, 3), np.float32),
    "ray_origin": ((512, 512, 3), np.float32),
    "ray_direction": ((512, 512, 3), np.float32),
    "mask": ((512, 512), np.bool_),
    "range": ((512, 512), np.float32),
    "ids": ((512, 512), np.uint32),
    "classes": ((512, 512), np.uint32),
}


def test_a_frame_is_a_dict_of_arrays_of_known_shapes(renderer):
    frame = renderer.render()
    assert set(frame) == set(SHAPES)
    for key, (shape, dtype) in SHAPES.items():
        assert frame[key].shape == shape, key
        assert frame[key].dtype == dtype, key
    # The arrays take over the engine's samples: no copy is kept elsewhere.
    assert frame["range"].base is not None and frame["range"].flags.c_contiguous


def test_the_layers_say_the_same_as_the_geometry(renderer, thesis):
    frame = renderer.render()
    mask = frame["mask"]
    # The thesis's sphere fills the middle of the sensor image, and only mirror pixels have rays.
    assert 0.3 < mask.mean() < 0.6
    assert not frame["ray_direction"][~mask].any() and not frame["range"][~mask].any()
    lengths = np.linalg.norm(frame["ray_direction"][mask], axis=-1)
    np.testing.assert_allclose(lengths, 1.0, atol=1e-5)
    # Every ray leaves the sphere's surface: 1 m from its centre (the scene frame's origin is
    # the mirror's centre here).
    assert thesis.origin == thesis.mirror_position
    radii = np.linalg.norm(frame["ray_origin"][mask], axis=-1)
    np.testing.assert_allclose(radii, 1.0, atol=1e-4)
    # A ray reaches what its id names: the room (ids 0..5) or the orbiter (6).
    assert set(np.unique(frame["ids"][mask])) <= set(range(7))
    assert (frame["ids"][~mask] == 2**32 - 1).all()
    # Each pixel's class is its id's: walls "wall" (0), the ceiling 1, the floor 2, and the
    # orbiter, which the scene gives no class, "object" (3).
    class_of = np.array([0, 0, 1, 2, 0, 0, 3], dtype=np.uint32)
    np.testing.assert_array_equal(frame["classes"][mask], class_of[frame["ids"][mask]])
    assert (frame["classes"][~mask] == 2**32 - 1).all()


def test_a_batch_is_the_frames_one_by_one_and_fills_given_buffers(renderer):
    poses = np.array([[0.0, 3.0, 0.0, 0.0], [1.0, 3.0, 0.5, 45.0]])
    singles = [renderer.render(pose=tuple(p), time=0.25) for p in poses]
    batch = renderer.render_batch(poses, times=[0.25])
    for key, (shape, dtype) in SHAPES.items():
        assert batch[key].shape == (2, *shape) and batch[key].dtype == dtype, key
        for b in range(2):
            assert np.array_equal(batch[key][b], singles[b][key]), key
    # The frames differ: the robot moved and turned.
    assert not np.array_equal(batch["sensor"][0], batch["sensor"][1])
    # Poses of another numeric type (ints, float32, a list) are the same poses.
    whole = np.array([[0, 3, 0, 0], [1, 3, 0, 45]], dtype=np.int64)
    for bad in (whole.astype(str), whole.astype(bool)):
        with pytest.raises(specchio.SpecchioError, match=r"poses: not an array of numbers \(dtype"):
            renderer.render_batch(bad)
    for same in (whole, whole.astype(np.float32), whole.tolist()):
        np.testing.assert_array_equal(renderer.render_batch(same, times=[0.25])["sensor"][1], renderer.render_batch(whole.astype(np.float64), times=[0.25])["sensor"][1])
    # out=: the same arrays, written again (the poses swapped).
    again = renderer.render_batch(poses[::-1].copy(), times=[0.25, 0.25], out=batch)
    for key in SHAPES:
        assert again[key] is batch[key]
        assert np.array_equal(batch[key][0], singles[1][key]), key


def test_wrong_buffers_and_poses_are_named(renderer):
    poses = np.array([[0.0, 3.0, 0.0, 0.0]])
    out = renderer.render_batch(poses)
    out["range"] = np.zeros((1, 512, 512), dtype=np.float64)
    with pytest.raises(specchio.SpecchioError, match=r'out\["range"\].*float32'):
        renderer.render_batch(poses, out=out)
    out["range"] = np.zeros((2, 512, 512), dtype=np.float32)
    with pytest.raises(specchio.SpecchioError, match=r'out\["range"\].*\(1, 512, 512\)'):
        renderer.render_batch(poses, out=out)
    with pytest.raises(specchio.SpecchioError, match=r"poses\[1\]: position: the mirror .* not entirely inside the room"):
        renderer.render_batch(np.array([[0.0, 3.0, 0.0, 0.0], [9.0, 3.0, 0.0, 0.0]]))
    with pytest.raises(specchio.SpecchioError, match=r"poses: 3 columns"):
        renderer.render_batch(np.zeros((1, 3)))
    with pytest.raises(specchio.SpecchioError, match=r"times: 3 values for 1 poses"):
        renderer.render_batch(poses, times=[0.0, 1.0, 2.0])
    # Each value is named by the argument it came from: `times`, `times[i]`, `pose`, `time`.
    with pytest.raises(specchio.SpecchioError, match=r"^times: must be a finite number of seconds"):
        renderer.render_batch(poses, times=[-1.0])
    with pytest.raises(specchio.SpecchioError, match=r"^times: must be a finite number of seconds"):
        renderer.render_batch(np.tile(poses, (2, 1)), times=[-1.0])
    with pytest.raises(specchio.SpecchioError, match=r"^times\[1\]: must be a finite number"):
        renderer.render_batch(np.tile(poses, (2, 1)), times=[0.0, np.nan])
    with pytest.raises(specchio.SpecchioError, match=r"^time: must be a finite number of seconds"):
        renderer.render(pose=(0.0, 3.0, 0.0, 0.0), time=np.nan)
    with pytest.raises(specchio.SpecchioError, match=r"^pose: heading: must be a finite number"):
        renderer.render(pose=(0.0, 3.0, 0.0, np.nan))
    # Refused before it is brought into one turn, which made 1e300 a 0.
    with pytest.raises(specchio.SpecchioError, match=r"^pose: heading: .* from -1e6 to 1e6"):
        renderer.render(pose=(0.0, 3.0, 0.0, 1e300))
    with pytest.raises(specchio.SpecchioError, match=r"^pose: position: the mirror .* not entirely inside the room"):
        renderer.render(pose=(100.0, 3.0, 0.0, 0.0))
    with pytest.raises(specchio.SpecchioError, match=r"poses\[0\]: position: every value"):
        renderer.render_batch(np.array([[np.nan, 3.0, 0.0, 0.0]]))
    with pytest.raises(specchio.SpecchioError, match=r"poses\[0\]: heading"):
        renderer.render_batch(np.array([[0.0, 3.0, 0.0, np.inf]]))
    # The same array for two layers, or a view of it, would be written over by both.
    shared = np.zeros((1, 512, 512, 3), dtype=np.float32)
    for other in (shared, shared[:], shared.reshape(1, 512, 512, 3)):
        with pytest.raises(specchio.SpecchioError, match=r'shares memory with out\[sensor\]'):
            renderer.render_batch(poses, out={"sensor": shared, "ray_origin": other})
    # A key that names no layer (misspelt) is refused, never left unfilled.
    with pytest.raises(specchio.SpecchioError, match=r"out\['sensors'\]: no such layer; .*\"sensor\""):
        renderer.render_batch(poses, out={"sensors": shared})
    with pytest.raises(specchio.SpecchioError, match=r"out\[0\]: no such layer"):
        renderer.render_batch(poses, out={0: shared})
    # A batch whose arrays would not fit the memory budget is refused, naming it.
    with pytest.raises(specchio.SpecchioError, match=r"poses: 100000 poses: .*fewer poses per batch"):
        renderer.render_batch(np.tile(poses, (100000, 1)))


def test_a_scene_error_names_file_line_and_field(tmp_path):
    text = scene_path("thesis-room").read_text().replace("radius = 1.0", "radius = -1.0", 1)
    assert "radius = -1.0" in text
    bad = tmp_path / "bad.toml"
    bad.write_text(text)
    # The scene's textures, where it names them.
    (tmp_path / "textures").symlink_to(scene_path("thesis-room").parent / "textures")
    with pytest.raises(specchio.SpecchioError) as e:
        specchio.Scene(bad)
    line = next(i for i, l in enumerate(text.splitlines(), 1) if "radius = -1.0" in l)
    assert f"bad.toml:{line}" in str(e.value) and "radius" in str(e.value)
    with pytest.raises(specchio.SpecchioError, match="missing.toml"):
        specchio.Scene(tmp_path / "missing.toml")


def test_lookups_and_devices_are_checked(thesis):
    with pytest.raises(specchio.SpecchioError, match="`mirror` is not a lookup"):
        specchio.Renderer(thesis, lookup="mirror")
    with pytest.raises(specchio.SpecchioError, match="no-such-device"):
        specchio.Renderer(thesis, device="no-such-device")
    # An index, as the docs say `device` takes: the device specchio.devices() lists there.
    first = next(d for d in specchio.devices() if d["usable"])
    with specchio.Renderer(thesis, device=first["index"]) as r:
        assert r.device == first["name"]
    # numpy's integers are indices too, as `spp` takes them.
    with specchio.Renderer(thesis, device=np.int64(first["index"])) as r:
        assert r.device == first["name"]
    for bad, says in [
        (-1, r"device: -1; must be a whole number"),
        (2**200, r"device: an int of 201 bits; must be a whole number"),
        (1.5, r"device: 1.5; give an index"),
        (True, r"device: True; give an index"),
    ]:
        with pytest.raises(specchio.SpecchioError, match=says):
            specchio.Renderer(thesis, device=bad)
    r = specchio.Renderer(thesis, lookup="plain")
    r.close()
    with pytest.raises(specchio.SpecchioError, match="closed"):
        r.render()


def test_a_wrong_type_is_named_by_its_argument(renderer, thesis, tmp_path):
    """Every argument of the wrong type raises SpecchioError naming it, what it was given
    and what it takes, in the message itself (PyO3's own TypeError names it only in a note,
    which str(e) leaves out)."""
    path = str(scene_path("thesis-room"))
    d = specchio.Descriptor()
    poses = np.zeros((1, 4))
    cases = [
        (lambda: specchio.pose_grid(thesis, "4"), r"^spacing: '4' \(a str\); give a number"),
        (lambda: specchio.pose_grid(thesis, 4.0, time=True), r"^time: True \(a bool\); give a number"),
        (lambda: specchio.pose_grid(thesis, 4.0, headings=1.5), r"^headings: 1.5 \(a float\); must be"),
        (lambda: specchio.reference("x.toml"), r"^scene: 'x.toml' \(a str\); give a specchio.Scene"),
        (lambda: specchio.reference(thesis, time="0"), r"^time: '0' \(a str\)"),
        (lambda: specchio.calibrate(thesis, tmp_path / "c", time=[0]), r"^time: \[0\] \(a list\)"),
        (lambda: specchio.Renderer(thesis, validate="yes"), r"^validate: 'yes' \(a str\); give True or False"),
        (lambda: specchio.Renderer(thesis, lookup=3), r"^lookup: 3 \(an int\); give a str"),
        (lambda: specchio.Scene(3), r"^path: 3 \(an int\); give a path"),
        (lambda: specchio.Scene(path, imaging=[]), r"^imaging: \[\] \(a list\); give a dict"),
        (lambda: specchio.read_exr(None), r"^path: None \(a NoneType\); give a path"),
        (lambda: specchio.read_trajectory(1.5), r"^path: 1.5 \(a float\); give a path"),
        (lambda: specchio.dataset(path, out=3, grid=4.0), r"^out: 3 \(an int\); give a path"),
        (lambda: specchio.dataset(path, out=str(tmp_path / "d"), grid="4"), r"^grid: '4' \(a str\)"),
        (lambda: specchio.Descriptor(name=3), r"^name: 3 \(an int\); give a str"),
        (lambda: d.distance("a", "b"), r"^a: 'a' \(a str\); give a specchio.Signature"),
        (lambda: d.distances(["x"], "q"), r"^database\[0\]: 'x' \(a str\); give a specchio.Signature"),
        (lambda: d.distances((), "q"), r"^query: 'q' \(a str\); give a specchio.Signature"),
        (lambda: renderer.render(time="0"), r"^time: '0' \(a str\)"),
        # A bool is no number, numpy's either, nor inside a pose or a list of times.
        (lambda: renderer.render(time=np.True_), r"^time: (np\.)?True_? \(a bool_?\); give a number"),
        (lambda: renderer.render(pose=(True, 3.0, 0.0, 0.0)), r"^pose: not an array of numbers \(a bool among them\)"),
        (lambda: renderer.render_batch(poses, times=[True]), r"^times\[0\]: True \(a bool\); give a number"),
        (lambda: renderer.render_batch(poses, times=[0.0, "1"]), r"^times\[1\]: '1' \(a str\); give a number"),
        (lambda: renderer.render_batch(poses, times="x"), r"^times: 'x' \(a str\); give a list of numbers"),
        (lambda: renderer.render_batch(poses, out=[1]), r"^out: \[1\] \(a list\); give a dict"),
        (lambda: specchio.localise(3, tmp_path / "l"), r"^scene: 3 \(an int\); give a path"),
        (
            lambda: specchio.dataset(path, out=str(tmp_path / "r"), grid=4.0, ray=True, shard_size="8"),
            r"^shard_size: '8' \(a str\); must be a whole number",
        ),
        (
            lambda: specchio.dataset(path, out=str(tmp_path / "p"), grid=4.0, progress=3),
            r"^progress: 3 \(an int\); give a function of \(done, total\)",
        ),
        # A truthy "no" would start a Ray cluster; refused before it does.
        (
            lambda: specchio.dataset(path, out=str(tmp_path / "n"), grid=4.0, ray="no"),
            r"^ray: 'no' \(a str\); give True or False",
        ),
        (
            lambda: specchio.dataset(path, out=str(tmp_path / "e"), grid=4.0, ray=True, worker_env=[1]),
            r"^worker_env: \[1\] \(a list\); give a dict of str to str",
        ),
        (
            lambda: specchio.dataset(path, out=str(tmp_path / "k"), grid=4.0, ray=True, worker_env={1: "x"}),
            r"^worker_env: the key 1 \(an int\); give variable names as str",
        ),
        (
            lambda: specchio.dataset(path, out=str(tmp_path / "v"), grid=4.0, ray=True, worker_env={"A": None}),
            r"^worker_env\['A'\]: None \(a NoneType\); give the value as a str",
        ),
    ]
    for call, says in cases:
        with pytest.raises(specchio.SpecchioError, match=says):
            call()
    # A long value is said by its type alone.
    with pytest.raises(specchio.SpecchioError, match=r"^time: a str; give a number"):
        renderer.render(time="x" * 1000)
    assert sorted(tmp_path.iterdir()) == []


@pytest.mark.parametrize("device", usable_devices())
def test_every_device_renders_and_says_where_its_labels_come_from(thesis, device):
    with specchio.Renderer(thesis, device=device) as r:
        frame = r.render(pose=(0.5, 3.0, 0.0, 30.0))
        # Traced labels on every device: ray queries where it has them, our own BVH else.
        assert (r.lookup, r.ground_truth) in {("ray-query", "traced"), ("bvh", "traced")}
        assert frame["mask"].any() and np.isfinite(frame["sensor"]).all()


THREADS = """
import sys, threading
import numpy as np
import specchio

renderer = specchio.Renderer(specchio.Scene(sys.argv[1]))
poses = [(0.0, 3.0, 0.0, 0.0), (1.0, 3.0, 0.5, 45.0)]
alone = [renderer.render(pose=p)["sensor"] for p in poses]
results = {}

def render(k):
    results[k] = [renderer.render(pose=poses[k])["sensor"] for _ in range(2)]

def read():
    results["read"] = [(renderer.device, renderer.lookup) for _ in range(1000)]

threads = [threading.Thread(target=f, args=a) for f, a in [(render, (0,)), (render, (1,)), (read, ())]]
for t in threads:
    t.start()
for t in threads:
    t.join()
assert all(np.array_equal(f, alone[k]) for k in (0, 1) for f in results[k])
assert len(results["read"]) == 1000
print("done")
"""


def test_threads_share_a_renderer_without_deadlock(tmp_path):
    """Renders run with the GIL released and take the renderer's lock only then: two threads
    rendering on one renderer while a third reads its properties all finish (a lock waited
    for while holding the GIL would hang the process: hence a child with a time limit), and
    each frame is the one its pose gives alone."""
    script = tmp_path / "threads.py"
    script.write_text(THREADS)
    run = subprocess.run(
        [sys.executable, str(script), str(scene_path("thesis-room"))],
        capture_output=True, text=True, timeout=300,
    )
    assert run.returncode == 0 and run.stdout.strip() == "done", run.stderr


def test_engine_warnings_are_python_warnings(tmp_path, capfd):
    """What the engine warns of is a Python warning, not a line on standard error, which a
    notebook never shows: SwiftShader leaving out the far floor of a 7 km room at 64² faces
    (its mechanism: tests/engine/hard_cases.rs). lavapipe draws it, and says nothing."""
    # Not a skip: this check needs SwiftShader, which scripts/setup.sh installs and
    # scripts/test.sh points Vulkan at (in CI usable_devices() itself insists).
    assert "swiftshader" in usable_devices(), "SwiftShader is not installed: run scripts/setup.sh"
    text = scene_path("hard/huge-room").read_text()
    assert "face_size = 256" in text
    path = tmp_path / "huge-room-64.toml"
    path.write_text(text.replace("face_size = 256", "face_size = 64"))
    scene = specchio.Scene(path)
    # A cube lookup: the default on SwiftShader, bvh, fills no cube. Python's filters decide:
    # made an error, the warning raises (a render places nothing, so it may). SwiftShader's is
    # said once a process, so one render shows both.
    with specchio.Renderer(scene, lookup="box", device="swiftshader") as r:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            with pytest.raises(UserWarning, match=r"^SwiftShader leaves out triangles of the room's ny wall"):
                r.render()
    assert "SwiftShader leaves out" not in capfd.readouterr().err
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with specchio.Renderer(scene, lookup="box", device="lavapipe") as r:
            r.render()
