"""Localisation's descriptors from Python: known answers on made-up panoramas, an independent
numpy version of the column-shift distance, and refusals that name the argument."""

import json
import math
import os
import re
import signal
import threading

import numpy as np
import pytest

import specchio
from conftest import cli, scene_path

W, H = 512, 64  # 128 column-shift columns of 4 pixels, 16 rows of 4


def place(seed, w=W, h=H):
    """A panorama of smooth random structure: a few harmonics per row band, in [0, 1]."""
    rng = np.random.default_rng(seed)
    az = (np.arange(w) + 0.5) / w * 2 * math.pi
    rows = []
    for r in range(h):
        band = r // 8
        phases = rng.uniform(0, 2 * math.pi, 4) if r % 8 == 0 else phases
        v = sum(np.cos((n + 1) * az + phases[n]) / (n + 1) for n in range(4)) + 0.3 * band
        rows.append(v)
    grey = np.array(rows)
    grey = (grey - grey.min()) / (grey.max() - grey.min())
    return np.stack([grey, 0.8 * grey, 1.0 - grey], axis=-1).astype(np.float32)


def grey(p):
    return 0.2126 * p[..., 0] + 0.7152 * p[..., 1] + 0.0722 * p[..., 2]


def column_shift_distance(a, b, columns=128):
    """The column-shift distance written from its definition (docs/sensor.md): grey levels
    box-filtered to `columns` columns and as many rows as keep the aspect ratio, compared as
    the root-mean-square difference at the best circular column shift."""
    h, w = a.shape[:2]
    rows = max(1, round(h * columns / w))

    def low(p):
        g = grey(p.astype(np.float64))
        return g.reshape(rows, h // rows, columns, w // columns).mean(axis=(1, 3))

    la, lb = low(a), low(b)
    return math.sqrt(min(np.mean((lb - np.roll(la, s, axis=1)) ** 2) for s in range(columns)))


def angle_error(a, b):
    return abs((a - b + math.pi) % (2 * math.pi) - math.pi)


def test_a_turned_robot_sees_the_same_place_and_its_turn_comes_back():
    d = specchio.Descriptor()
    assert (d.name, d.k) == ("column-shift", 8)
    base = d.describe(place(1))
    assert base.columns == 128 and base.values.shape == (16 * 128,)
    for cells in [0, 1, 37, 127]:
        turned = d.describe(np.roll(place(1), 4 * cells, axis=1))
        assert d.distance(base, turned) < 1e-6
        assert angle_error(d.turn(base, turned), cells / 128 * 2 * math.pi) < 1e-9
    assert d.distance(base, d.describe(place(2))) > 0.05


def test_the_fourier_signature_forgets_the_heading_and_its_phases_give_it_back():
    d = specchio.Descriptor("fourier", k=8)
    base = d.describe(place(3))
    assert base.columns == W and base.values.shape == (H * 8 * 2,)
    for pixels in [5, 200, 511]:
        turned = d.describe(np.roll(place(3), pixels, axis=1))
        assert d.distance(base, turned) < 1e-3
        assert angle_error(d.turn(base, turned), pixels / W * 2 * math.pi) < 0.1 * 2 * math.pi / W


def test_the_column_shift_distance_is_its_definition():
    d = specchio.Descriptor()
    a, b = place(4), np.roll(place(5), 9, axis=1)
    want = column_shift_distance(a, b)
    got = d.distance(d.describe(a), d.describe(b))
    assert want > 0.05
    assert abs(got - want) <= 1e-5 * want


def test_distances_rank_a_database():
    d = specchio.Descriptor()
    database = [d.describe(place(s)) for s in range(6)]
    query = d.describe(np.roll(place(4), 40, axis=1))
    got = d.distances(database, query)
    assert got.dtype == np.float64 and got.shape == (6,)
    assert list(got) == [d.distance(s, query) for s in database]
    assert int(np.argmin(got)) == 4


def test_integers_and_rgba_are_panoramas_too():
    d = specchio.Descriptor()
    p = place(6)
    rgba = np.concatenate([p, np.ones((H, W, 1), np.float32)], axis=-1)
    assert d.distance(d.describe(p), d.describe(rgba)) == 0.0
    ints = (p * 1000).astype(np.int32)
    assert d.describe(ints).columns == 128


@pytest.mark.parametrize(
    "make, needle",
    [
        (lambda: specchio.Descriptor("sift"), "name: \"sift\" is not a descriptor"),
        (lambda: specchio.Descriptor(k=0), "k: 0; must be a whole number from 1 to 256"),
        (lambda: specchio.Descriptor(k=257), "k: 257"),
        (lambda: specchio.Descriptor(k=2**200), "k: an int of 201 bits; must be a whole number"),
        (lambda: specchio.Descriptor().describe(np.zeros((4, 8))), "panorama: an array of shape [4, 8]"),
        (lambda: specchio.Descriptor().describe(np.zeros((0, 8, 3))), "panorama: an array of shape [0, 8, 3]"),
        (lambda: specchio.Descriptor().describe([["a"]]), "panorama: not an array of numbers"),
        # Past what the panorama holds: every larger k would describe it alike.
        (
            lambda: specchio.Descriptor(k=33).describe(np.zeros((4, 512, 3))),
            "k=33: column-shift takes at most 32 for a panorama 512 columns wide",
        ),
        (
            lambda: specchio.Descriptor("fourier", k=10).describe(np.zeros((4, 16, 3))),
            "k=10: fourier takes at most 9 for a panorama 16 columns wide",
        ),
        (
            lambda: specchio.Descriptor().describe(np.full((2, 3, 3), np.nan)),
            "panorama: [0, 0, 0] is NaN",
        ),
    ],
)
def test_bad_arguments_are_refused_by_name(make, needle):
    with pytest.raises(specchio.SpecchioError, match=None) as e:
        make()
    assert needle in str(e.value)


def test_a_panorama_too_large_to_copy_is_refused_before_the_copy(monkeypatch):
    """A broadcast view costs nothing to pass and its copies 372 GiB: they are measured
    against the memory budget before any is made, and refused naming `panorama`."""
    monkeypatch.setenv("SPECCHIO_MEMORY_BUDGET", "1G")
    huge = np.broadcast_to(np.float32(0.5), (100000, 100000, 3))
    with pytest.raises(specchio.SpecchioError, match=r"panorama: this run would need about 372\.5 GiB"):
        specchio.Descriptor().describe(huge)


def test_signatures_of_another_descriptor_or_size_are_refused():
    shift, fourier = specchio.Descriptor(), specchio.Descriptor("fourier")
    a = shift.describe(place(7))
    with pytest.raises(specchio.SpecchioError) as e:
        shift.distance(a, fourier.describe(place(7)))
    assert "b: a fourier k=8 signature, given to column-shift k=8" in str(e.value)
    with pytest.raises(specchio.SpecchioError) as e:
        shift.turn(a, shift.describe(place(7, w=256)))
    assert "panoramas of different sizes" in str(e.value)
    with pytest.raises(specchio.SpecchioError) as e:
        shift.distances([a, specchio.Descriptor(k=4).describe(place(7))], a)
    assert "database[1]: a column-shift k=4 signature, given to column-shift k=8" in str(e.value)


def _untimed(report):
    """A localise report without what depends on the clock (the sweeps' seconds and rates)."""
    report = json.loads(json.dumps(report))
    for source in report["sources"]:
        source.pop("sweep_seconds")
        source.pop("sweep_images_per_s")
    for row in report["rows"]:
        row.pop("landmark_images_per_s")
    return report


def test_localise_runs_the_commands_experiment(tmp_path):
    """specchio.localise is `specchio localise`: with the same options the same report (but
    for the times the sweep took) and the same landmarks file; queries at the landmarks all
    find their own. Options are checked as the command checks them, with nothing written."""
    scene = str(scene_path("thesis-room"))
    options = {"grid": 4, "queries": 8, "queries_at_landmarks": True, "seed": 5,
               "sensor_size": 64, "cube_size": 32, "times": [0], "validate": False}
    report = specchio.localise(scene, tmp_path / "py", **options)
    flags = ["--grid", "4", "--queries", "8", "--queries-at-landmarks", "--seed", "5",
             "--sensor-size", "64", "--cube-size", "32", "--times", "0"]
    run = cli("localise", scene, "--out", "cli", *flags, cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    written = json.loads((tmp_path / "py" / "localise.json").read_text())
    assert report == written
    want = json.loads((tmp_path / "cli" / "localise.json").read_text())
    assert _untimed(report) == _untimed(want)
    assert sorted(p.name for p in (tmp_path / "py").iterdir()) == sorted(
        p.name for p in (tmp_path / "cli").iterdir()
    )
    assert (tmp_path / "py" / "landmarks.json").read_bytes() == (
        tmp_path / "cli" / "landmarks.json"
    ).read_bytes()
    (row,) = report["rows"]
    assert row["summary"]["queries"] == 8 and row["summary"]["recall_at_1"] == 1.0
    # numpy's values read as Python's: the same report from an array of times and a numpy bool.
    again = specchio.localise(scene, tmp_path / "numpy", **{**options, "times": np.array([0]),
                                                             "queries_at_landmarks": np.True_})
    assert _untimed(again) == _untimed(report)
    for bad, says in [({"queries": 0}, "--queries"), ({"bogus": 1}, "--bogus"),
                      ({"descriptor": "sift"}, "`sift` is not a descriptor"),
                      ({"seed": -1}, "'-1' for '--seed"), ({"descriptor": "--help"}, "--help"),
                      # A bool is no value, a dict no list (its keys were taken as one).
                      ({"queries": True}, "queries: True (a bool); --queries takes a value"),
                      ({"seed": {"a": 1}}, "seed: a dict; give the option's value")]:
        with pytest.raises(specchio.SpecchioError, match=re.escape(says)):
            specchio.localise(scene, tmp_path / "bad", **{**options, **bad})
        assert not (tmp_path / "bad").exists()


def test_localise_stops_at_ctrl_c_with_nothing_written(tmp_path):
    """Ctrl-C (a SIGINT a quarter second in, while the landmarks are swept: some 1,300 of
    them at 0.25 m) raises KeyboardInterrupt and leaves no output."""
    scene = str(scene_path("thesis-room"))
    # Python's own Ctrl-C handler, whatever this process inherited: a job started in the
    # background of a script ignores SIGINT, and Python then keeps ignoring it.
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    timer = threading.Timer(0.25, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            specchio.localise(scene, tmp_path / "stopped", grid=0.25, sensor_size=64, cube_size=32)
    finally:
        timer.cancel()
        signal.signal(signal.SIGINT, before)
    assert not (tmp_path / "stopped").exists()
    assert not [p for p in tmp_path.iterdir() if "stopped" in p.name]
