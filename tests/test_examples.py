"""Every script in examples/ runs, at its small size (``--small``), as a user would run it."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

import sigmapi

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = sorted((ROOT / "examples").glob("*.py"))
NEEDS = {"compare_baselines.py": ("sklearn", "minisom")}


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
    r = subprocess.run(
        [sys.executable, str(path), "--small"], capture_output=True, text=True, timeout=300,
        cwd=tmp_path, env={**os.environ, "PYTHONPATH": src},
    )  # fmt: skip
    assert r.returncode == 0, r.stderr[-2000:]
    if path.name != "compare_baselines.py":
        # the maps order: thresholds: order R^2 >= 0.95 on every seed printed
        orders = [float(v) for v in re.findall(r"order R\^2 ([0-9.]+)", r.stdout)]
        assert orders and min(orders) >= 0.95, r.stdout
    else:
        assert "sigma-pi" in r.stdout and (tmp_path / "compare.png").is_file()
