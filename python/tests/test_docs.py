"""docs/python.md's example, run as a user would: from a folder with the checkout's scenes."""

from __future__ import annotations

import re
import subprocess
import sys

from conftest import ROOT


def test_the_documented_example_runs_and_prints_what_it_says(tmp_path):
    text = (ROOT / "docs" / "python.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, re.S)
    assert len(blocks) == 1, "docs/python.md has one example"
    (tmp_path / "scenes").symlink_to(ROOT / "scenes")
    (tmp_path / "example.py").write_text(blocks[0])
    run = subprocess.run(
        [sys.executable, "example.py"], cwd=tmp_path, capture_output=True, text=True
    )
    assert run.returncode == 0, run.stderr
    # Each `# ...` comment after a print in the example is what that line prints.
    promised = [
        c.strip()
        for line in blocks[0].splitlines()
        if line.lstrip().startswith("print(") and "  # " in line
        for c in [line.split("  # ", 1)[1]]
    ]
    assert len(promised) >= 4
    for line in promised:
        assert line in run.stdout, f"{line!r} not in:\n{run.stdout}"
    assert (tmp_path / "out" / "robot" / "dataset.json").is_file()
    assert sorted(p.name for p in (tmp_path / "out" / "robot").rglob("*")) == sorted(
        p.name for p in (tmp_path / "out" / "robot-ray").rglob("*")
    )
