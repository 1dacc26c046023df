"""The maps at the learning rule's ceiling: the presets on seeds not tuned on.

Usage (from the repository root)::

    python benchmarks/bench_ceiling.py                          # paper-1d, paper-2d; seeds 700-719
    python benchmarks/bench_ceiling.py --presets paper-1d --seeds 700 701

Trains each preset on each seed (its own procedure: ordered start, training, refinement),
evaluates the map (:func:`sigmapi.evaluate`, 10,000 test z's) and writes
``benchmarks/results/ceiling.json``: per seed the metrics, the wall seconds of the training
and of the refinement, the process CPU seconds (of the training and in all), and the
machine's load average (with ``--ceiling`` also the metrics of the map's fixed point of
Eq. 7, the rule's own ceiling); per preset the median and worst seed of every metric, how many
seeds ordered (order R^2 >= 0.95) and folded, and how many meet each target of
:data:`TARGETS`.
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
from sigmapi.config import apply_overrides

ROOT = Path(__file__).resolve().parent
METRICS = ("view_consistency", "view_within_one", "z_error", "order_r2", "fold_score")
CIRCULAR = ("order_circular", "seam_jump", "seam_gap")
"""The circular metrics of a map of angles (:mod:`sigmapi.metrics.circular`), recorded when
present."""
WORST = {"z_error": max, "fold_score": max, "seam_jump": max, "seam_gap": max}
"""Metrics where larger is worse; for the rest smaller is worse."""
TIMES = ("train_s", "train_cpu_s", "refine_s", "total_s", "cpu_s")
TARGETS: dict[str, dict[str, tuple[str, float]]] = {
    "paper-1d": {"order_r2": (">=", 0.95), "view_consistency": (">=", 0.90),
                 "z_error": ("<=", 0.30), "train_cpu_s": ("<=", 5.0)},
    "paper-2d": {"order_r2": (">=", 0.95), "view_consistency": (">=", 0.60),
                 "view_within_one": (">=", 0.98), "z_error": ("<=", 0.566),
                 "cpu_s": ("<=", 60.0)},
}  # fmt: skip
"""The acceptance targets of each preset (docs/guide/ceiling.md): per run, metric or time
(``cpu_s``: training and refinement, CPU seconds of the process) against a bound."""


def run_seed(
    preset: str, seed: int, overrides: list[str] | None = None, ceiling: bool = False
) -> dict[str, Any]:
    """One seed of ``preset`` (with ``key=value`` ``overrides``): metrics and times; for a map
    of angles also the circular metrics and ``seamless``. ``ceiling``: also the metrics of
    the rule's fixed point reached from the map (:func:`sigmapi.analysis.fixed_point.fixed_point`,
    after the times are taken)."""
    cfg = apply_overrides(sigmapi.load_preset(preset), overrides or []).replace(seed=seed)
    model = SigmaPiSOM(cfg)
    marks: list[tuple[float, float]] = []
    t0, c0 = time.perf_counter(), time.process_time()

    def mark(m: SigmaPiSOM) -> None:
        if not marks and m.t_ >= cfg.iterations:
            marks.append((time.perf_counter() - t0, time.process_time() - c0))

    model.fit(callback=mark)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    train, train_cpu = marks[0] if marks else (wall, cpu)
    r = evaluate(model).to_dict()
    circular = {k: float(r[k]) for k in CIRCULAR if k in r}
    if "seamless" in r:
        circular["seamless"] = bool(r["seamless"])
    if ceiling:
        from sigmapi.analysis.fixed_point import fixed_point

        fp = fixed_point(model)
        fm = fp.metrics.to_dict()
        circular["ceiling"] = {
            **{k: float(fm[k]) for k in METRICS},
            "rounds": fp.rounds, "converged": fp.converged,
        }  # fmt: skip
    return {
        "seed": seed,
        **{k: float(r[k]) for k in METRICS},
        **circular,
        "folded": bool(r["folded"]),
        "train_s": round(train, 2),
        "train_cpu_s": round(train_cpu, 2),
        "refine_s": round(wall - train, 2),
        "total_s": round(wall, 2),
        "cpu_s": round(cpu, 2),
        "load_avg_1min": round(os.getloadavg()[0], 2),
    }


def summary(runs: list[dict[str, Any]], preset: str = "") -> dict[str, Any]:
    """Median and worst seed of every metric and time; seeds ordered and folded; per target
    of ``preset`` (:data:`TARGETS`) how many seeds meet it and how many measured it (a run
    may lack a time), and how many meet all."""
    out: dict[str, Any] = {"seeds": len(runs)}
    for k in (*METRICS, *CIRCULAR, *TIMES):
        vals = [r[k] for r in runs if k in r]
        if not vals:
            continue
        worst = WORST.get(k, min) if k in METRICS else max
        out[k] = {"median": float(np.median(vals)), "worst": float(worst(vals))}
    ceilings = [r["ceiling"] for r in runs if "ceiling" in r]
    if ceilings:
        out["ceiling"] = {
            k: {"median": float(np.median([c[k] for c in ceilings])),
                "worst": float(WORST.get(k, min)([c[k] for c in ceilings]))}
            for k in ("view_consistency", "z_error")
        }  # fmt: skip
        out["ceiling"]["converged"] = sum(bool(c["converged"]) for c in ceilings)
    out["ordered"] = sum(r["order_r2"] >= 0.95 for r in runs)
    out["folded"] = sum(bool(r.get("folded", False)) for r in runs)
    if any("seamless" in r for r in runs):
        out["seamless"] = sum(bool(r.get("seamless", False)) for r in runs)
        out["seamless_and_order_circular_0.95"] = sum(
            bool(r.get("seamless", False)) and r["order_circular"] >= 0.95 for r in runs
        )
    targets = TARGETS.get(preset, {})
    if targets:
        meets = [{k: meets_target(r, k, *t) for k, t in targets.items()} for r in runs]
        out["targets"] = {k: f"{op} {bound:g}" for k, (op, bound) in targets.items()}
        out["meeting"] = {k: sum(bool(m[k]) for m in meets) for k in targets}
        out["measured"] = {k: sum(m[k] is not None for m in meets) for k in targets}
        out["meeting_all"] = sum(all(m.values()) for m in meets)
    return out


def meets_target(run: dict[str, Any], key: str, op: str, bound: float) -> bool | None:
    """Whether ``run[key]`` meets ``op bound`` (None if the run lacks the key)."""
    if key not in run:
        return None
    return bool(run[key] >= bound if op == ">=" else run[key] <= bound)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--presets", nargs="*", default=["paper-1d", "paper-2d"])
    parser.add_argument("--seeds", nargs="*", type=int, default=list(range(700, 720)))
    parser.add_argument(
        "--set",
        dest="overrides",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="a config override for every preset (TOML)",
    )
    parser.add_argument("--label", default="", help="the result's name (default: the preset's)")
    parser.add_argument(
        "--ceiling", action="store_true",
        help="also score each map's fixed point of Eq. 7 (sigmapi.analysis.fixed_point; "
        "2-D: ~70 CPU s)",
    )  # fmt: skip
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
        name = args.label or preset
        cfg = apply_overrides(sigmapi.load_preset(preset), args.overrides).to_dict()
        for seed in args.seeds:
            runs.append(run_seed(preset, seed, args.overrides, args.ceiling))
            print(name, json.dumps(runs[-1]), flush=True)
            result["presets"][name] = {"preset": preset, "overrides": args.overrides,
                                       "config": cfg, "summary": summary(runs, name),
                                       "runs": runs}  # fmt: skip
            write_json(Path(args.out), result)
        print(name, json.dumps(result["presets"][name]["summary"]), flush=True)


def write_json(path: Path, data: dict[str, Any]) -> None:
    """Write ``data`` to ``path`` atomically (a temporary file renamed over it)."""
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(data, indent=1) + "\n", encoding="utf-8")
    os.replace(tmp, path)


if __name__ == "__main__":
    main()
