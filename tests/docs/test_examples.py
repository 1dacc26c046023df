"""Every script in examples/ runs, at its small size (``--small``), as a user would run it."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

import sigmapi

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = sorted((ROOT / "examples").glob("*.py"))
NEEDS = {"compare_baselines.py": ("sklearn", "minisom"), "robot.py": ("mujoco",)}
FIGURES = {"compare_baselines.py": "sigma-pi", "noise.py": "caption: noise in every code",
           "robot.py": "docking on map"}  # fmt: skip
"""Examples that draw a figure (``--out``), and a line their output must hold."""


def test_every_example_is_named_in_the_readme():
    readme = (ROOT / "README.md").read_text("utf-8")
    assert EXAMPLES
    for path in EXAMPLES:
        assert f"examples/{path.name}" in readme, path.name


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.name)
def test_example_runs_small(path, tmp_path):
    for module in NEEDS.get(path.name, ()):
        pytest.importorskip(module)
    src = str(Path(sigmapi.__file__).resolve().parents[1])
    out = ["--out", f"{path.stem}.png"] if path.name in FIGURES else []
    r = subprocess.run(
        [sys.executable, str(path), "--small", *out], capture_output=True, text=True, timeout=300,
        cwd=tmp_path, env={**os.environ, "PYTHONPATH": src},
    )  # fmt: skip
    assert r.returncode == 0, r.stderr[-2000:]
    if path.name in FIGURES:
        assert FIGURES[path.name] in r.stdout and (tmp_path / f"{path.stem}.png").is_file()
    else:  # the maps order: threshold: order R^2 >= 0.95 on every seed printed
        orders = [float(v) for v in re.findall(r"order R\^2 ([0-9.]+)", r.stdout)]
        assert orders and min(orders) >= 0.95, r.stdout
