"""specchio: an omnidirectional catadioptric camera (a camera looking at a mirror) simulated
on Vulkan, with exact ground truth, calibration and datasets as numpy arrays.

    import specchio
    scene = specchio.Scene("scenes/thesis-room.toml")
    with specchio.Renderer(scene) as r:
        frame = r.render(pose=(0.0, 1.5, 0.0, 90.0))   # x, y, z (m), heading (deg)
        frame["sensor"]   # (H, W, 3) float32, linear RGB

See docs/python.md for the whole package: batches, the exact reference, calibration and
datasets, in one process or on Ray.
"""

from __future__ import annotations

import os
from typing import Any, Callable, Optional, Union

from ._specchio import (
    DatasetFrames,
    DatasetOutput,
    Descriptor,
    Renderer,
    Scene,
    Signature,
    SpecchioError,
    __version__,
    calibrate,
    devices,
    localise,
    pose_grid,
    read_exr,
    read_trajectory,
    reference,
)
from ._args import flag, function_or_none
from ._specchio import dataset as _dataset_here

__all__ = [
    "DatasetFrames",
    "DatasetOutput",
    "Descriptor",
    "Renderer",
    "Scene",
    "Signature",
    "SpecchioError",
    "__version__",
    "calibrate",
    "dataset",
    "devices",
    "localise",
    "pose_grid",
    "read_exr",
    "read_trajectory",
    "reference",
]

Path = Union[str, "os.PathLike[str]"]


def dataset(
    scene: Path,
    trajectory: Optional[Path] = None,
    out: Optional[Path] = None,
    *,
    grid: Optional[float] = None,
    headings: Optional[int] = None,
    time: Optional[float] = None,
    lookup: Optional[str] = None,
    device: Optional[Union[int, str]] = None,
    validate: bool = False,
    progress: Optional[Callable[[int, int], None]] = None,
    resume: bool = False,
    ray: bool = False,
    workers: Optional[int] = None,
    shard_size: int | None = None,
    worker_env: Optional[dict] = None,
    panorama_frame: str = "robot",
    outputs: Optional[Union[str, list[str]]] = None,
    format: Optional[Union[str, list[str]]] = None,
    geometry_frame: str = "scene",
) -> dict[str, Any]:
    """Renders the dataset of ``scene`` along ``trajectory`` (CSV or JSON, docs/sensor.md)
    into the folder ``out``, as ``specchio dataset`` does: per pose a folder of the sensor
    image, ray map, range, ids, panoramas, camera.json, pose.json (scene frame and ROS
    REP-103) and a point cloud; ``index.jsonl``; ``dataset.json``. All or nothing: every
    pose is checked first, and the folder appears only when every frame is written.

    Instead of a trajectory, ``grid=SPACING`` (metres) stands the robot at every place of a
    square grid over the floor where it fits, turned to ``headings`` headings (default 1) at
    the scene time ``time`` (default 0): ``specchio dataset --grid``, the same poses as
    ``pose_grid``. For example ``specchio.dataset(scene, out="grid", grid=1.0, headings=8)``.

    ``resume=True`` keeps each finished frame in ``out.partial`` beside the output, and goes
    on from the frames it holds when the same dataset was stopped before (Ctrl-C, a crash, a
    lost Ray cluster), in this process or on Ray alike; refused when the inputs, the lookup
    or the device differ from that run's (``specchio dataset --resume``, docs/sensor.md).

    ``ray=True`` renders on Ray (``specchio.ray.dataset``): ``workers`` actors (default: the
    cluster's CPUs) each hold a renderer and take shards of ``shard_size`` poses (default 8;
    ``workers``, ``worker_env`` and ``shard_size`` are refused without ``ray=True``); the files
    are the same, byte for byte. Ray is started locally unless it is running already or
    ``RAY_ADDRESS`` names a cluster. ``worker_env``: environment variables of the workers
    (e.g. ``{"LP_NUM_THREADS": "1"}`` for lavapipe with one thread each).

    ``panorama_frame``: whose frame the panoramas' columns are in: ``"robot"`` (its forward
    axis at the left edge; they turn with it, as a real robot's do) or ``"world"`` (the
    scene's +X at the left edge whatever the heading: made with the true heading, which a
    robot does not know). ``specchio dataset --panorama-frame``, docs/sensor.md.

    ``outputs``: the layers each frame holds, as a list (``["image", "range", "ids"]``) or a
    comma-separated string: ``image``, ``camera`` (with the scene's ``[sensor.imaging]``),
    ``rays``, ``range``, ``range16`` (the range as 16-bit millimetres, ``sensor.range.png``;
    named only, not in ``"all"``), ``ids``, ``panoramas``, ``points``; or ``"all"`` (every
    layer the scene has); or ``"default"`` (what ``None`` gives: every layer but ``rays`` and
    ``points``, which the pose and one frame's ray map give again). ``camera.json`` and
    ``pose.json`` always. ``specchio dataset --outputs``, docs/sensor.md.

    ``format``: ``"files"`` (the default: the frame folders and ``index.jsonl``), ``"mcap"``
    (a ROS 2 bag in ``out/bag``, ``metadata.yaml`` and ``bag_0.mcap``, made from the frames,
    which are then not kept) or ``"files,mcap"`` (or a list). ``specchio dataset --format``,
    docs/sensor.md "ROS 2 bags".

    ``geometry_frame``: the frame of the ray map and the point cloud: ``"scene"`` (local, +Y up,
    as every other output), ``"map"`` (ROS REP-103's world) or ``"base_link"`` (the robot's
    REP-103 frame, where a rigid sensor's ray map is the same at every pose). ``specchio
    dataset --geometry-frame``, docs/sensor.md.

    ``progress(done, total)`` is called as frames are written. Returns the summary
    (``dataset.json``) as a dict.
    """
    if out is None:
        raise SpecchioError("out: the dataset's folder is required")
    function_or_none("progress", progress)
    flag("ray", ray)
    if ray:
        from . import ray as _ray

        return _ray.dataset(
            scene,
            trajectory,
            out,
            grid=grid,
            headings=headings,
            time=time,
            lookup=lookup,
            device=device,
            validate=validate,
            progress=progress,
            resume=resume,
            workers=workers,
            shard_size=8 if shard_size is None else shard_size,
            worker_env=worker_env,
            panorama_frame=panorama_frame,
            outputs=outputs,
            format=format,
            geometry_frame=geometry_frame,
        )
    if workers is not None or worker_env is not None or shard_size is not None:
        raise SpecchioError("workers, worker_env and shard_size are for ray=True")
    return _dataset_here(
        scene,
        trajectory,
        out,
        grid=grid,
        headings=headings,
        time=time,
        lookup=lookup,
        device=device,
        validate=validate,
        progress=progress,
        resume=resume,
        panorama_frame=panorama_frame,
        outputs=outputs,
        format=format,
        geometry_frame=geometry_frame,
    )

