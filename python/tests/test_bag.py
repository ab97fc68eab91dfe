"""A dataset as a ROS 2 bag (`format="mcap"`), read back by two independent readers: `rosbags`
(rosbag2's metadata.yaml and the MCAP storage, every message deserialised with the ROS 2
Humble definitions, whose type hashes the bag's schemas must equal) and the `mcap` package;
each topic holds what the frame folders hold."""

from __future__ import annotations

import json
import pathlib

import numpy as np
import pytest
from mcap.reader import make_reader
from rosbags.highlevel import AnyReader
from rosbags.typesys import Stores, get_typestore

import specchio
from conftest import ROBOT_CSV, SCENES, scene_path

CAMERA = "\n[sensor.imaging]\nexposure_s = 0.004\nseed = 5\n"
TOPICS = {
    "/tf_static", "/tf", "/odom", "/camera/camera_info", "/camera/image_raw",
    "/camera/image_clean", "/sensor/range", "/camera/ids", "/camera/classes", "/camera/points",
}


def camera_room(tmp_path: pathlib.Path) -> str:
    path = tmp_path / "room.toml"
    path.write_text(scene_path("thesis-room").read_text() + CAMERA)
    # Its textures, where the scene's relative paths look for them.
    (tmp_path / "textures").symlink_to(SCENES / "textures")
    return str(path)


def quat_rotate(q, v):
    """Rotates v by the unit quaternion q = (x, y, z, w)."""
    u, w = np.array(q[:3]), q[3]
    v = np.asarray(v, float)
    return v + 2.0 * np.cross(u, np.cross(u, v) + w * v)


def messages(bag: pathlib.Path):
    """Every message, deserialised: {topic: [(time, message)]}, and the connections."""
    humble = get_typestore(Stores.ROS2_HUMBLE)
    out: dict[str, list] = {}
    with AnyReader([bag], default_typestore=humble) as reader:
        for c in reader.connections:
            # The schema in the bag is the Humble definition, to the hash.
            assert reader.typestore.hash_rihs01(c.msgtype) == humble.hash_rihs01(c.msgtype), c.topic
        for c, t, raw in reader.messages():
            out.setdefault(c.topic, []).append((t, reader.deserialize(raw, c.msgtype)))
        return out, {c.topic: c.msgtype for c in reader.connections}


def ply_points(path: pathlib.Path) -> np.ndarray:
    data = path.read_bytes()
    body = data[data.index(b"end_header\n") + 11:]
    return np.frombuffer(body, dtype=[("p", "<f4", 3), ("id", "<u4")])


def test_the_bag_holds_what_the_frames_hold(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "robot.csv").write_text(ROBOT_CSV)
    # Every layer: the default leaves out the point cloud /camera/points carries.
    record = specchio.dataset(camera_room(tmp_path), "robot.csv", "both", format="files,mcap", outputs="all")
    assert record["format"] == ["files", "mcap"]
    out = tmp_path / "both"
    topics, types = messages(out / "bag")
    assert set(topics) == TOPICS
    assert types["/camera/points"] == "sensor_msgs/msg/PointCloud2"
    lines = [json.loads(line) for line in (out / "index.jsonl").read_text().splitlines()]
    assert len(lines) == 5 and all(len(topics[t]) == 5 for t in TOPICS - {"/tf_static"})
    (stamp, static), = topics["/tf_static"]
    mount = {t.child_frame_id: t for t in static.transforms}["camera_optical"]
    assert mount.header.frame_id == "base_link"
    origin = np.array(json.loads((out / "dataset.json").read_text())["scene_origin_m"])
    for i, line in enumerate(lines):
        frame = out / line["folder"]
        ros = line["ros"]
        t_ns = round(line["time_s"] * 1e9) + 10**9  # a second on: ROS reads 0 as "latest"
        at = {topic: msgs[i][1] for topic, msgs in topics.items() if topic != "/tf_static"}
        assert all(msgs[i][0] == t_ns for topic, msgs in topics.items() if topic != "/tf_static")
        (base,) = at["/tf"].transforms
        assert (base.header.frame_id, base.child_frame_id) == ("odom", "base_link")
        tr, q = base.transform.translation, base.transform.rotation
        assert [tr.x, tr.y, tr.z] == ros["base_link_position_m"]
        assert np.allclose([q.x, q.y, q.z, q.w], ros["base_link_quaternion_xyzw"], atol=1e-12)
        # base_link then the static mount: the camera where pose.json puts it.
        m = mount.transform
        camera = np.array([tr.x, tr.y, tr.z]) + quat_rotate(
            [q.x, q.y, q.z, q.w], [m.translation.x, m.translation.y, m.translation.z]
        )
        assert np.allclose(camera, ros["camera_optical_position_m"], atol=1e-9)

        exr_range = specchio.read_exr(frame / "sensor.range.exr")["range"]
        rng = at["/sensor/range"]
        assert (rng.encoding, rng.height, rng.width, rng.step) == ("32FC1", 512, 512, 2048)
        got = rng.data.view("<f4").reshape(512, 512)
        # NaN for no return (REP-117), where the file says 0.
        assert np.array_equal(got, np.where(exr_range == 0, np.nan, exr_range), equal_nan=True)
        assert np.isnan(got).any() and not np.isnan(exr_range).any()
        ids = specchio.read_exr(frame / "sensor.id.exr")
        for topic, channel in (("/camera/ids", "id"), ("/camera/classes", "class")):
            got = at[topic].data.view("<i4").reshape(512, 512)
            assert np.array_equal(got, ids[channel].astype(np.uint32).view(np.int32)), topic

        raw = at["/camera/image_raw"]
        assert (raw.encoding, raw.is_bigendian, raw.step) == ("rgb16", 0, 512 * 6)
        codes = raw.data.view("<u2")
        assert not (codes & 0xF).any(), "a 12-bit code in the top bits of 16"
        assert at["/camera/image_clean"].encoding == "rgb8"
        info = at["/camera/camera_info"]
        sensor = json.loads((frame / "camera.json").read_text())["sensor"]
        assert info.k[0] == pytest.approx(sensor["focal_px"][0])
        # camera.json counts from pixel (0, 0)'s corner, ROS from its centre.
        assert info.k[2] == pytest.approx(sensor["principal_point_px"][0] - 0.5)
        assert info.k[5] == pytest.approx(sensor["principal_point_px"][1] - 0.5)
        assert info.header.frame_id == "camera_optical"

        # The cloud, taken back to map through the camera's pose, is the PLY's.
        cloud = at["/camera/points"]
        pts = cloud.data.view(np.dtype([("p", "<f4", 3), ("id", "<u4")]))
        ply = ply_points(frame / "points.ply")
        assert np.array_equal(pts["id"], ply["id"])
        cam_q = ros["camera_optical_quaternion_xyzw"]
        back = np.array([quat_rotate(cam_q, p) for p in pts["p"][::997].astype(float)])
        back += ros["camera_optical_position_m"]
        local = ply["p"][::997].astype(float) + origin
        want = np.stack([local[:, 0], -local[:, 2], local[:, 1]], axis=1)
        assert np.abs(back - want).max() < 1e-4

    # The first frame's velocity: the first segment's, in base_link's axes (heading 0).
    p0, p1 = (np.array(lines[k]["ros"]["base_link_position_m"]) for k in (0, 1))
    twist = topics["/odom"][0][1].twist.twist
    assert np.allclose([twist.linear.x, twist.linear.y, twist.linear.z], (p1 - p0) / 0.5)
    assert twist.angular.z == pytest.approx(np.radians(45) / 0.5)

    # The official MCAP reader takes the file, its summary and every message.
    with open(out / "bag" / "bag_0.mcap", "rb") as f:
        reader = make_reader(f)
        assert reader.get_header().profile == "ros2"
        total = reader.get_summary().statistics.message_count
        assert total == sum(1 for _ in reader.iter_messages()) == 1 + 9 * 5


def test_a_bag_alone_on_ray_is_the_same_bag(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "robot.csv").write_text(ROBOT_CSV)
    scene = str(scene_path("thesis-room"))
    specchio.dataset(scene, "robot.csv", "here", format="mcap", outputs="image,range,range16")
    record = specchio.dataset(
        scene, "robot.csv", "ray", format=["mcap"], outputs="image,range,range16", ray=True, workers=1,
        shard_size=3, worker_env={"LP_NUM_THREADS": "1"},
    )
    assert (record["format"], record["index"]) == (["mcap"], None)
    for out in ("here", "ray"):
        assert sorted(p.name for p in (tmp_path / out).iterdir()) == [
            ".specchio-files", "bag", "dataset.json"
        ], "no frame folders, no index"
    for name in ("bag_0.mcap", "metadata.yaml"):
        assert (tmp_path / "here" / "bag" / name).read_bytes() == (
            tmp_path / "ray" / "bag" / name
        ).read_bytes(), name
    topics, _ = messages(tmp_path / "here" / "bag")
    assert set(topics) == {"/tf_static", "/tf", "/odom", "/camera/camera_info",
                           "/camera/image_clean", "/sensor/range", "/sensor/range_mm"}
    # The millimetres are the metres rounded, 0 for no return (REP-117's integer convention).
    for (_, metres), (_, mm) in zip(topics["/sensor/range"], topics["/sensor/range_mm"]):
        assert (mm.encoding, mm.step) == ("16UC1", 512 * 2)
        m = metres.data.view("<f4")
        # Halves round up (numpy's round would take them to even).
        want = np.where(np.isnan(m), 0, np.floor(m.astype(np.float64) * 1000 + 0.5)).astype(np.uint16)
        assert np.array_equal(mm.data.view("<u2"), want)
        assert (want > 0).mean() > 0.4


def test_a_bad_format_writes_nothing_and_says_why(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "robot.csv").write_text(ROBOT_CSV)
    scene = str(scene_path("thesis-room"))
    for fmt, says in (("bag", "format: `bag` is not a format"), (7, r"^format: 7 \(an int\); give a str")):
        with pytest.raises(specchio.SpecchioError, match=says):
            specchio.dataset(scene, "robot.csv", "bad", format=fmt)
        assert not (tmp_path / "bad").exists()


def mei_project(p: np.ndarray, d: list[float], k: list[float]) -> np.ndarray:
    """Mei's unified model as OpenCV's omnidir.projectPoints defines it, from the bag's
    `d = [xi, k1, k2, p1, p2]` and K."""
    xi, k1, k2, p1, p2 = d
    s = p / np.linalg.norm(p, axis=1, keepdims=True)
    x, y = s[:, 0] / (s[:, 2] + xi), s[:, 1] / (s[:, 2] + xi)
    r2 = x * x + y * y
    radial = 1 + k1 * r2 + k2 * r2 * r2
    xd = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
    yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
    return np.stack([k[0] * xd + k[1] * yd + k[2], k[4] * yd + k[5]], axis=1)


def test_a_central_mirrors_bag_carries_its_unified_model(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "robot.csv").write_text("time,x,y,z,heading\n0,0,3,0,0\n1,0.5,3,0.3,40\n")
    scene = str(scene_path("hyperbolic-room"))
    specchio.dataset(scene, "robot.csv", "out", format="files,mcap", outputs="range,points")
    # The rays' mask says which pixels the cloud's points come from, in pixel order.
    out = tmp_path / "out"
    topics, _ = messages(out / "bag")
    static = {t.child_frame_id: t for t in topics["/tf_static"][0][1].transforms}
    camera, omni = static["camera_optical"].transform, static["omni"].transform
    assert static["omni"].header.frame_id == "camera_optical"
    # The viewpoint is the inner focus, d = 2 m up the camera's axis: base_link's origin.
    view = [omni.translation.x, omni.translation.y, omni.translation.z]
    assert np.allclose(view, [0, 0, 2], atol=1e-6)
    assert camera.translation.z + omni.translation.z == pytest.approx(0, abs=1e-6)
    for i in range(2):
        info = topics["/omni/camera_info"][i][1]
        assert (info.distortion_model, info.header.frame_id) == ("mei", "omni")
        assert info.d[0] == pytest.approx(2 / np.sqrt(5), abs=1e-6), "xi = d / sqrt(d² + 4p²)"
        # Each mirror pixel's point, moved to omni and into the model's left-handed frame,
        # projects back onto that pixel.
        frame = out / f"frames/{i:06d}"
        rng = topics["/sensor/range"][i][1].data.view("<f4").reshape(512, 512)
        rows, cols = np.nonzero(~np.isnan(rng))
        cloud = topics["/camera/points"][i][1]
        pts = cloud.data.view(np.dtype([("p", "<f4", 3), ("id", "<u4")]))["p"].astype(float)
        assert len(pts) == len(rows)
        model = pts - view
        model[:, 2] *= -1
        pixels = mei_project(model[::101], list(info.d), list(info.k))
        want = np.stack([cols[::101], rows[::101]], axis=1)
        # 9e-5 px measured: the cloud's float32 points.
        assert np.abs(pixels - want).max() < 1e-3, np.abs(pixels - want).max()
    with open(out / "bag" / "bag_0.mcap", "rb") as f:
        names = sorted(a.name for a in make_reader(f).iter_attachments())
    assert names == ["kalibr_camchain.yaml", "ocamcalib_calib_results.txt", "opencv_omnidir.yaml"]


def test_a_bag_without_the_unified_model_says_so(tmp_path, monkeypatch):
    """A central mirror whose sensor is too large to calibrate gets no /omni/camera_info: the
    Ray driver's half says so when it is made (before any frame), as the command does."""
    monkeypatch.chdir(tmp_path)
    text = scene_path("hyperbolic-room").read_text()
    big = text.replace("resolution = [512, 512]", "resolution = [4100, 4100]")
    # Its assets, from the shipped scene's folder.
    big = big.replace('"textures/', f'"{SCENES}/textures/').replace('"meshes/', f'"{SCENES}/meshes/')
    assert big != text
    scene = tmp_path / "big.toml"
    scene.write_text(big)
    (tmp_path / "robot.csv").write_text("time,x,y,z,heading\n0,0,3,0,0\n")
    with pytest.warns(UserWarning, match=r"no unified model \(/omni/camera_info\): sensor.resolution 4100x4100"):
        output = specchio.DatasetOutput(str(scene), "robot.csv", "out", format="mcap")
    del output
    # Without a bag there is nothing to miss, and nothing is said.
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        specchio.DatasetOutput(str(scene), "robot.csv", "out2", format="files")
