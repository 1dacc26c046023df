"""Sweep throughput: runs per hour on the local executor against one run at a time.

Usage (from the repository root)::

    python benchmarks/bench_sweep.py                    # paper-2d, 4 seeds: ~6 min on 2 cores
    python benchmarks/bench_sweep.py --preset tiny-1d   # a first look, seconds

Writes ``benchmarks/results/sweep.json``. The same sweep (``--preset``, seeds 0 .. n-1, no
grid) runs twice in one benchmark run, in fresh output folders: once with ``--workers 1``
(one run at a time, in the sweep's own process) and once with the local executor's default
plan (a process pool, one worker per core as the memory budget allows). Both pass through
``sigmapi.experiments.sweep.run.run_sweep``; reported: wall seconds, runs per hour, their ratio,
the workers used, and the check that both tables hold the same metrics.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent


def _spec(preset: str, n_seeds: int, iterations: int | None) -> str:
    text = f'preset = "{preset}"\nseeds = {list(range(n_seeds))}\nn_test = 2000\n'
    if iterations is not None:
        text += f"[set]\niterations = {iterations}\n"
    return text


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--preset", default="paper-2d")
    parser.add_argument("--seeds", type=int, default=4)
    parser.add_argument("--iterations", type=int, default=None,
                        help="override the preset's run length")  # fmt: skip
    parser.add_argument("--out", default=str(ROOT / "results" / "sweep.json"))
    args = parser.parse_args()

    from sigmapi.executor import plan_workers
    from sigmapi.experiments.sweep.run import SweepSpec, run_sweep

    spec = SweepSpec.from_toml(_spec(args.preset, args.seeds, args.iterations))
    machine = {"cpus": os.cpu_count(), "platform": platform.platform(),
               "python": sys.version.split()[0]}  # fmt: skip
    iterations = spec.runs()[0].config.iterations
    result: dict[str, object] = {"machine": machine, "preset": args.preset,
                                 "seeds": args.seeds, "iterations": iterations}  # fmt: skip
    tables = {}
    with tempfile.TemporaryDirectory() as tmp:
        for label, workers in (("one_at_a_time", 1), ("local_executor", None)):
            plan = plan_workers(workers, 1)
            t0 = time.perf_counter()
            rows = run_sweep(spec, Path(tmp) / label, workers=workers)
            wall = time.perf_counter() - t0
            tables[label] = {r["run_id"]: round(float(r["order_r2"]), 6) for r in rows}
            train = sorted(float(r["train_seconds"]) for r in rows)
            result[label] = {"workers": plan.workers, "wall_seconds": round(wall, 1),
                             "runs_per_hour": round(3600 * len(rows) / wall, 1),
                             "median_train_seconds": round(train[len(train) // 2], 1)}  # fmt: skip
            print(f"{label}: {result[label]}", file=sys.stderr)
    one, pool = result["one_at_a_time"], result["local_executor"]
    assert isinstance(one, dict) and isinstance(pool, dict)
    result["speedup"] = round(pool["runs_per_hour"] / one["runs_per_hour"], 2)
    result["same_metrics"] = tables["one_at_a_time"] == tables["local_executor"]
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(result, indent=2) + "\n")
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
