"""The maps at the learning rule's ceiling (issue 21): the presets on seeds not tuned on.

Usage (from the repository root)::

    python benchmarks/bench_ceiling.py                          # paper-1d, paper-2d; 600-619
    python benchmarks/bench_ceiling.py --presets paper-1d --seeds 600 601

Trains each preset on each seed (its own procedure: ordered start, training, refinement),
evaluates the map (:func:`sigmapi.evaluate`, 10,000 test z's) and writes
``benchmarks/results/ceiling.json``: per seed the metrics, the wall seconds of the training
and of the refinement, the process CPU seconds, and the machine's load average; per preset
the median and worst seed of every metric, and how many seeds ordered (order R^2 >= 0.95).
The refinement's progress is measured by the callback's first call past the training. Wall
times depend on what else runs on the machine: the load average is recorded beside them.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

import sigmapi
from sigmapi import SigmaPiSOM, evaluate

ROOT = Path(__file__).resolve().parent
METRICS = ("view_consistency", "view_within_one", "z_error", "order_r2", "fold_score")
WORST = {"z_error": max, "fold_score": max}  # larger is worse; else smaller is worse


def run_seed(preset: str, seed: int) -> dict[str, Any]:
    """One seed of ``preset``: metrics and times."""
    cfg = sigmapi.load_preset(preset).replace(seed=seed)
    model = SigmaPiSOM(cfg)
    marks: list[float] = []
    t0, c0 = time.perf_counter(), time.process_time()

    def mark(m: SigmaPiSOM) -> None:
        if not marks and m.t_ >= cfg.iterations:
            marks.append(time.perf_counter() - t0)

    model.fit(callback=mark)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    train = marks[0] if marks else wall
    r = evaluate(model).to_dict()
    return {
        "seed": seed,
        **{k: float(r[k]) for k in METRICS},
        "train_s": round(train, 2),
        "refine_s": round(wall - train, 2),
        "total_s": round(wall, 2),
        "cpu_s": round(cpu, 2),
        "load_avg_1min": round(os.getloadavg()[0], 2),
    }


def summary(runs: list[dict[str, Any]]) -> dict[str, Any]:
    """Median and worst seed of every metric and time; seeds ordered."""
    out: dict[str, Any] = {"seeds": len(runs)}
    for k in (*METRICS, "train_s", "refine_s", "total_s", "cpu_s"):
        vals = [r[k] for r in runs]
        worst = WORST.get(k, min) if k in METRICS else max
        out[k] = {"median": float(np.median(vals)), "worst": float(worst(vals))}
    out["ordered"] = sum(r["order_r2"] >= 0.95 for r in runs)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--presets", nargs="*", default=["paper-1d", "paper-2d"])
    parser.add_argument("--seeds", nargs="*", type=int, default=list(range(600, 620)))
    parser.add_argument("--out", default=str(ROOT / "results" / "ceiling.json"))
    args = parser.parse_args()
    # compile the kernels first, so that the first seed's times are the run's
    SigmaPiSOM(sigmapi.load_preset("tiny-1d"), iterations=2000, refine_rounds=1,
               refine_pairs=1000, seed=0).fit()  # fmt: skip
    result: dict[str, Any] = {
        "command": "python benchmarks/bench_ceiling.py " + " ".join(sys.argv[1:]),
        "machine": f"{platform.machine()}, {os.cpu_count()} cores, shared (see load_avg_1min)",
        "presets": {},
    }
    for preset in args.presets:
        runs = []
        for seed in args.seeds:
            runs.append(run_seed(preset, seed))
            print(preset, json.dumps(runs[-1]), flush=True)
            cfg = sigmapi.load_preset(preset).to_dict()
            result["presets"][preset] = {"config": cfg, "summary": summary(runs), "runs": runs}
            Path(args.out).write_text(json.dumps(result, indent=1) + "\n", encoding="utf-8")
        print(preset, json.dumps(result["presets"][preset]["summary"]), flush=True)


if __name__ == "__main__":
    main()
