"""The gain-field studies' protocol (sigmapi.analysis.monkey) on model files, as
``sigmapi physiology MODEL --json`` reports it under ``"monkey"``, summarised over seeds.

    sigmapi train --preset paper-2d --seed S --out p2d_S.npz     # S = 110..114
    python benchmarks/bench_monkey.py p2d_110.npz p2d_111.npz p2d_112.npz p2d_113.npz p2d_114.npz

Each model is recorded with the default eye grid (5 positions per gaze axis) and with the
studies' 3 x 3 (``0.3,0.5,0.7``). The defaults (eye grid, :data:`RESPONDS`) were chosen on
paper-2d seed 0; seeds 110-114 are fresh. Writes ``benchmarks/results/physiology-monkey.json``
(per model and the median and worst over the models of each number).
"""

from __future__ import annotations

import argparse
import json
import platform
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from sigmapi.analysis.monkey import EYE_GRID, monkey_protocol
from sigmapi.io import atomic_write_bytes
from sigmapi.model.som import load_model

OUT = Path(__file__).resolve().parent / "results" / "physiology-monkey.json"

GRIDS = {"default": EYE_GRID, "studies-3x3": (0.3, 0.5, 0.7)}

KEYS = (
    "admitted_share",
    "gain_modulated_share",
    "gain_r2",
    "gain_ratio",
    "reference_frame_index",
    "reference_frame_index_all",
    "reference_frame_index_left_out",
    "displacement_index",
)


def _number(row: dict[str, Any], key: str) -> float | None:
    v = row[key]
    return v["median"] if isinstance(v, dict) else v


def _row(path: Path, grid: tuple[float, ...]) -> dict[str, Any]:
    r = monkey_protocol(load_model(path), grid)
    return {
        "model": path.name,
        "units": r["units"],
        "admitted": r["admitted"],
        "left_out": r["left_out"],
        **{k: r[k] for k in KEYS},
        "reference_frame_index_quartiles": r["reference_frame_index"]["quartiles"],
    }


def _summary(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """Median over the models of each number (a distribution's median per model) and the
    worst: the lowest, except the all-units and left-out indices and the gain R^2, whose
    range is given."""
    out: dict[str, Any] = {}
    for key in KEYS:
        vals = np.array([v for r in rows if (v := _number(r, key)) is not None], dtype=float)
        if vals.size:
            out[key] = {"median": float(np.median(vals)), "min": float(vals.min()),
                        "max": float(vals.max()), "n_models": int(vals.size)}  # fmt: skip
    return out


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("models", nargs="+", type=Path)
    p.add_argument("--out", type=Path, default=OUT)
    args = p.parse_args(argv)
    start, cpu = time.perf_counter(), time.process_time()
    result: dict[str, Any] = {
        "command": " ".join(["python benchmarks/bench_monkey.py", *(m.name for m in args.models)]),
        "grids": {k: list(v) for k, v in GRIDS.items()},
    }
    for name, grid in GRIDS.items():
        rows = [_row(m, grid) for m in args.models]
        result[name] = {"rows": rows, "summary": _summary(rows)}
        print(name, json.dumps(result[name]["summary"], indent=1))
    result["seconds"] = time.perf_counter() - start
    result["cpu_s"] = time.process_time() - cpu
    result["machine"] = {"python": platform.python_version(), "platform": platform.platform()}
    text = json.dumps(result, indent=1) + "\n"
    atomic_write_bytes(args.out, text.encode("utf-8"))
    print(f"wrote {args.out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
