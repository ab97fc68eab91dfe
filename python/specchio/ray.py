"""Datasets rendered by a pool of Ray workers (``specchio.dataset(..., ray=True)``).

One actor per worker holds a renderer of the robot (``DatasetFrames``); the poses are cut
into shards, and each shard is a task on whichever actor is free. A frame's files come back
to the driver as bytes (so the workers need no shared file system, only the scene, its
assets and the trajectory at the same paths), and the driver alone writes the output folder,
all or nothing (``DatasetOutput``). A frame's bytes depend only on the plan, the lookup, the
device and the frame's pose, never on which worker rendered it or what it rendered before,
so the folder is the same, byte for byte, as a single process's.

A worker that dies (its process killed, its node lost) is restarted and its shard retried
(``max_restarts``, ``max_task_retries``); an error of the engine (a scene it cannot render)
is raised at once, since a retry would fail the same way.

Ray starts locally (the embedded default) unless it is running already, or ``RAY_ADDRESS``
names a cluster to join (``ray start --head`` on one machine, ``ray start --address=HEAD:6379``
on the others; docs/python.md).
"""

from __future__ import annotations

import math
import os
from typing import Any, Callable, Optional, Union

from ._args import environment, whole
from ._specchio import DatasetFrames, DatasetOutput, SpecchioError

#: How often Ray restarts a dead worker, and retries the shard it held.
RETRIES = 2


class _Worker:
    """A Ray actor: one renderer of the dataset's robot."""

    def __init__(self, scene: str, trajectory: Optional[str], plan: dict, lookup, device, validate: bool):
        # An engine error here is kept and said by `describe`: raised, it would reach the
        # driver as Ray's "actor died", its message buried in a traceback.
        self.frames, self.error = None, None
        try:
            # One encoder: a worker shares its machine with as many others as it has CPUs,
            # and each encoder holds a frame in memory.
            self.frames = DatasetFrames(
                scene, trajectory, lookup=lookup, device=device, validate=validate, encoders=1, **plan
            )
        except SpecchioError as e:
            self.error = str(e)

    def describe(self) -> tuple[Optional[str], str, str, str]:
        if self.frames is None:
            return (self.error, "", "", "")
        return (None, self.frames.lookup, self.frames.ground_truth, self.frames.device)

    def render(self, indices: list[int]):
        # A worker restarted where its renderer cannot be made: the engine's own error.
        if self.frames is None:
            raise SpecchioError(self.error)
        # What rendered the frames: a worker restarted elsewhere may have another device.
        f = self.frames
        return indices, f.frames(indices), (f.lookup, f.ground_truth, f.device)


def init_options() -> dict[str, Any]:
    """How ``dataset`` starts Ray when it is not running: joining ``RAY_ADDRESS``'s cluster,
    or a local one (``address=None``), its workers' output kept out of the driver's."""
    return {"address": os.environ.get("RAY_ADDRESS") or None, "log_to_driver": False}


def dataset(
    scene,
    trajectory,
    out,
    *,
    grid: Optional[float] = None,
    headings: Optional[int] = None,
    time: Optional[float] = None,
    lookup: Optional[str] = None,
    device: Optional[Union[int, str]] = None,
    validate: bool = False,
    progress: Optional[Callable[[int, int], None]] = None,
    resume: bool = False,
    workers: Optional[int] = None,
    shard_size: int = 8,
    worker_env: Optional[dict] = None,
    panorama_frame: str = "robot",
    outputs: Optional[Union[str, list[str]]] = None,
    format: Optional[Union[str, list[str]]] = None,
    geometry_frame: str = "scene",
) -> dict[str, Any]:
    """``specchio.dataset`` on Ray; see its documentation."""
    import ray
    from ray.util import ActorPool

    whole("shard_size", shard_size)
    if workers is not None:
        whole("workers", workers)
    worker_env = environment("worker_env", worker_env)
    # Where the poses come from, whose frame the panoramas are in and which layers the frames
    # hold: the driver's output and every worker's renderer make the same plan of them.
    plan = {
        "grid": grid,
        "headings": headings,
        "time": time,
        "panorama_frame": panorama_frame,
        "outputs": outputs,
        "geometry_frame": geometry_frame,
    }
    # Every input is checked, and the output staged, before any worker starts.
    # The bag is made by the driver, from the frames the workers rendered.
    output = DatasetOutput(scene, trajectory, out, resume=resume, format=format, **plan)
    # Paths, checked by DatasetOutput (a str or an os.PathLike).
    scene, out = os.fspath(scene), os.fspath(out)
    trajectory = None if trajectory is None else os.fspath(trajectory)
    n = len(output)
    started = not ray.is_initialized()
    if started:
        ray.init(**init_options())
    actors = []
    try:
        count = workers or max(1, int(ray.cluster_resources().get("CPU", 1)))
        # At least one, even when a resumed run has nothing left: it names the device.
        count = max(1, min(count, math.ceil(n / shard_size)))
        options: dict[str, Any] = {
            "num_cpus": 1,
            "max_restarts": RETRIES,
            "max_task_retries": RETRIES,
        }
        if worker_env:
            options["runtime_env"] = {"env_vars": worker_env}
        worker = ray.remote(**options)(_Worker)
        # The workers read the files themselves: absolute paths, whatever their directory.
        paths = (os.path.abspath(scene), trajectory and os.path.abspath(trajectory))
        actors = [worker.remote(*paths, plan, lookup, device, validate) for _ in range(count)]
        described = set(ray.get([a.describe.remote() for a in actors]))
        failed = sorted(error for error, _, _, _ in described if error is not None)
        if failed:
            raise SpecchioError(failed[0])
        runs = {(lookup, truth) for _, lookup, truth, _ in described}
        devices = sorted({device for _, _, _, device in described})
        if len(runs) != 1 or (resume and len(devices) != 1):
            raise SpecchioError(
                f"the workers' devices differ: lookups and ground truths {sorted(runs)}, "
                f"devices {devices}; name one device (device=...) that every worker has"
            )
        (chosen_lookup, truth) = runs.pop()
        # The frames a resumed run still lacks (all of them otherwise), and no more workers
        # than their shards.
        todo = output.begin(chosen_lookup, truth, devices[0])
        shards = [todo[i : i + shard_size] for i in range(0, len(todo), shard_size)]
        for a in actors[max(1, len(shards)) :]:
            ray.kill(a)
        actors = actors[: max(1, len(shards))]
        done = n - len(todo)
        pool = ActorPool(actors)
        for indices, frames, used in pool.map_unordered(lambda a, s: a.render.remote(s), shards):
            if used[:2] != (chosen_lookup, truth) or (resume and used[2] != devices[0]):
                raise SpecchioError(
                    f"a restarted worker renders with {used}, not the run's "
                    f"{(chosen_lookup, truth, devices[0])}: name one device (device=...) that "
                    "every worker has"
                )
            for files, line in frames:
                output.place(files, line)
            done += len(indices)
            if progress is not None:
                progress(done, n)
        if not shards and progress is not None:
            progress(n, n)
        return output.finish(chosen_lookup, truth)
    except ray.exceptions.RayTaskError as e:
        # The engine's own error, raised in a worker: the same exception, the same message.
        output.close()
        if isinstance(e.cause, SpecchioError):
            error = SpecchioError(*e.cause.args)
            output.note_kept(error)
            raise error from None
        output.note_kept(e)
        raise
    except BaseException as e:
        # Whatever stopped the run (Ctrl-C, a dead actor, a lost cluster): the staged files
        # go now, not when Python collects the traceback that holds `output`; then say what a
        # resumable run kept.
        output.close()
        output.note_kept(e)
        raise
    finally:
        for a in actors:
            ray.kill(a)
        if started:
            ray.shutdown()
