"""What the benchmark scripts share: running a measurement in a fresh process, the machine's
description, writing the JSON result."""

from __future__ import annotations

import json
import os
import platform
import subprocess
import sys
from pathlib import Path
from typing import Any


def run_child(script: str | Path, args: list[str], src: Path | None = None) -> dict[str, Any]:
    """Run ``script --child *args`` in a fresh process (``src``: put it first on PYTHONPATH);
    returns the JSON object it prints last, plus nothing else."""
    env = None if src is None else dict(os.environ, PYTHONPATH=str(src))
    cmd = [sys.executable, str(Path(script).resolve()), "--child", *args]
    proc = subprocess.run(cmd, capture_output=True, text=True, env=env, check=False)
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed:\n{proc.stderr[-3000:]}")
    return dict(json.loads(proc.stdout.strip().splitlines()[-1]))


def commit(src: Path | None) -> str | None:
    """The git commit of the checkout holding ``src`` (None if there is none)."""
    if src is None:
        return None
    proc = subprocess.run(
        ["git", "-C", str(src), "rev-parse", "HEAD"], capture_output=True, text=True, check=False
    )
    return proc.stdout.strip() or None


def machine(**extra: Any) -> dict[str, Any]:
    """The platform, CPU count, load average now and Python version (and ``extra``)."""
    return {
        "platform": platform.platform(),
        "processor": platform.processor(),
        "cpus": os.cpu_count(),
        "load_average_at_end": os.getloadavg(),
        "python": platform.python_version(),
        **extra,
    }


def write_result(path: Path, result: dict[str, Any]) -> None:
    """Write ``result`` as sorted, indented JSON (a file a person can diff)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(result, indent=1, sort_keys=True) + "\n", encoding="utf-8")
    print(f"wrote {path}")
