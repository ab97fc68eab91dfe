"""Typed stubs of the native module (python/src/); the documentation is on the objects."""

from os import PathLike
from pathlib import Path
from typing import Any, Callable, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

_Path = Union[str, PathLike[str]]
_Pose = tuple[float, float, float, float]
# A device: its index in specchio.devices(), or part of its name.
_Device = Union[int, str]
Frame = dict[str, npt.NDArray[Any]]

__version__: str

class SpecchioError(Exception): ...

class Scene:
    def __init__(self, path: _Path) -> None: ...
    @property
    def path(self) -> Path: ...
    @property
    def sensor_size(self) -> tuple[int, int]: ...
    @property
    def observer_size(self) -> tuple[int, int]: ...
    @property
    def mirror_shape(self) -> str: ...
    @property
    def mirror_position(self) -> tuple[float, float, float]: ...
    @property
    def origin(self) -> tuple[float, float, float]: ...
    @property
    def objects(self) -> list[str]: ...

class Renderer:
    def __init__(
        self,
        scene: Scene,
        lookup: Optional[str] = None,
        device: Optional[_Device] = None,
        validate: bool = False,
    ) -> None: ...
    @property
    def device(self) -> str: ...
    @property
    def lookup(self) -> str: ...
    @property
    def ground_truth(self) -> str: ...
    def render(self, pose: Optional[_Pose] = None, time: float = 0.0) -> Frame: ...
    def render_batch(
        self,
        poses: npt.ArrayLike,
        times: Optional[Sequence[float]] = None,
        out: Optional[Frame] = None,
    ) -> Frame: ...
    def close(self) -> None: ...
    def __enter__(self) -> "Renderer": ...
    def __exit__(self, *args: Any) -> bool: ...

class DatasetFrames:
    def __init__(
        self,
        scene: _Path,
        trajectory: Optional[_Path],
        lookup: Optional[str] = None,
        device: Optional[_Device] = None,
        validate: bool = False,
        encoders: Optional[int] = None,
        grid: Optional[float] = None,
        headings: Optional[int] = None,
        time: Optional[float] = None,
        panorama_frame: str = "robot",
        outputs: Optional[Union[str, list[str]]] = None,
        geometry_frame: str = "scene",
    ) -> None: ...
    def __len__(self) -> int: ...
    @property
    def lookup(self) -> str: ...
    @property
    def ground_truth(self) -> str: ...
    @property
    def device(self) -> str: ...
    def frames(self, indices: list[int]) -> list[tuple[list[tuple[str, bytes]], str]]: ...

class DatasetOutput:
    def __init__(
        self,
        scene: _Path,
        trajectory: Optional[_Path],
        out: _Path,
        resume: bool = False,
        grid: Optional[float] = None,
        headings: Optional[int] = None,
        time: Optional[float] = None,
        panorama_frame: str = "robot",
        outputs: Optional[Union[str, list[str]]] = None,
        format: Optional[Union[str, list[str]]] = None,
        geometry_frame: str = "scene",
    ) -> None: ...
    def __len__(self) -> int: ...
    @property
    def work_folder(self) -> Optional[str]: ...
    def begin(self, lookup: str, ground_truth: str, device: str) -> list[int]: ...
    def place(self, files: list[tuple[str, bytes]], index_line: str) -> None: ...
    def finish(self, lookup: str, ground_truth: str) -> dict[str, Any]: ...
    def note_kept(self, error: BaseException) -> None: ...
    def close(self) -> None: ...

def devices() -> list[dict[str, Any]]: ...
def pose_grid(
    scene: Scene, spacing: float, headings: int = 1, time: float = 0.0
) -> npt.NDArray[np.float64]: ...
def read_exr(path: _Path) -> dict[str, npt.NDArray[Any]]: ...
def read_trajectory(path: _Path) -> list[dict[str, Any]]: ...
def reference(
    scene: Scene, pose: Optional[_Pose] = None, time: float = 0.0, spp: int = 1
) -> Frame: ...
def calibrate(scene: Scene, out: _Path, time: float = 0.0) -> dict[str, Any]: ...
def dataset(
    scene: _Path,
    trajectory: Optional[_Path],
    out: _Path,
    lookup: Optional[str] = None,
    device: Optional[_Device] = None,
    validate: bool = False,
    progress: Optional[Callable[[int, int], None]] = None,
    resume: bool = False,
    grid: Optional[float] = None,
    headings: Optional[int] = None,
    time: Optional[float] = None,
    panorama_frame: str = "robot",
    outputs: Optional[Union[str, list[str]]] = None,
    format: Optional[Union[str, list[str]]] = None,
    geometry_frame: str = "scene",
) -> dict[str, Any]: ...
