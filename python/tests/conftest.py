"""Shared fixtures of the Python package's tests (run by scripts/test.sh, which builds the
wheel first and sets SPECCHIO_VALIDATE=1: any validation message raises)."""

from __future__ import annotations

import os
import pathlib
import subprocess

import pytest

import specchio

ROOT = pathlib.Path(__file__).resolve().parents[2]
SCENES = ROOT / "scenes"


def scene_path(name: str) -> pathlib.Path:
    return SCENES / f"{name}.toml"


@pytest.fixture(scope="session")
def thesis() -> specchio.Scene:
    return specchio.Scene(scene_path("thesis-room"))


@pytest.fixture(scope="session")
def renderer(thesis):
    with specchio.Renderer(thesis) as r:
        yield r


def usable_devices() -> list[str]:
    """Every device the engine can use here, by short name: in CI (which sets
    SPECCHIO_REQUIRE_TOOL_CHECKS) both CPU drivers, lavapipe and SwiftShader, must be there."""
    names = [d["short_name"] for d in specchio.devices() if d["usable"]]
    if os.environ.get("SPECCHIO_REQUIRE_TOOL_CHECKS") and not {"lavapipe", "swiftshader"} <= set(names):
        raise RuntimeError(f"the tests need lavapipe and SwiftShader; the devices here: {names}")
    return names


def cli(*args: str, cwd: pathlib.Path) -> subprocess.CompletedProcess:
    """Runs the `specchio` command (SPECCHIO_BIN, set by scripts/test.sh)."""
    binary = os.environ.get("SPECCHIO_BIN")
    if not binary or not os.access(binary, os.X_OK):
        raise RuntimeError(
            "SPECCHIO_BIN must name the built `specchio` binary (scripts/test.sh sets it)"
        )
    return subprocess.run([binary, *args], cwd=cwd, capture_output=True, text=True)


def tree(folder: pathlib.Path) -> dict[str, bytes]:
    """Every file under `folder`: relative path -> bytes."""
    return {
        str(p.relative_to(folder)): p.read_bytes()
        for p in sorted(folder.rglob("*"))
        if p.is_file()
    }


ROBOT_CSV = """time,x,y,z,heading
0,0,3,0,0
0.5,1,3,0.5,45
1,1.5,3,1,90
1.5,0.5,3,-1,200
2,-1,3,0.5,300
"""
