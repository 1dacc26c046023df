"""The torus at the refinement: a 10x10 periodic map on two angles, before and after it.

Usage (from the repository root)::

    python benchmarks/bench_torus.py                                  # both variants, seeds 0-2
    python benchmarks/bench_torus.py --variants w10-mind --seeds 0 1 2 3 4 5 6 7 8 9

A 10x10 torus (``map_periodic``) on 10x10 periodic codes, ``relation = "sum_mod"`` in both
dimensions (z = (x + y) mod 1 per axis), the paper's random start (``ordering = "none"``;
the ``cv-`` variants start from the cross-view start), one refinement round of 100,000 pairs
after the training. Each variant (:data:`VARIANTS`) sets the code width, winner rule,
schedule and refinement. Per seed: the
metrics of :func:`sigmapi.evaluate` (the circular ones of :mod:`sigmapi.metrics.circular`) at the
end of the training and after the refinement, and the process CPU seconds; per variant
how many seeds end seamless with circular order >= 0.95. Writes
``benchmarks/results/ceiling-torus.json``.
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

from sigmapi import SigmaPiSOM, SOMConfig, evaluate

ROOT = Path(__file__).resolve().parent
KEYS = ("view_consistency", "view_within_one", "z_error", "order_circular", "seam_gap",
        "seam_jump", "seamless")  # fmt: skip
BASE: dict[str, Any] = dict(
    map_shape=(10, 10), x_shape=(10, 10), y_shape=(10, 10), periodic=True, map_periodic=True,
    relation="sum_mod", code_height=1.0, code_normalize=True, soft_cut=15, init_scale=0.1,
    kernel_tol=1e-4, ordering="none", refine_rounds=1, refine_pairs=100_000, refine_sigma=0.0,
)  # fmt: skip
VARIANTS: dict[str, dict[str, Any]] = {
    # paper-2d's rule and schedule at width 1.0
    "w10-mind": dict(code_width=1.0, winner_rule="min_distance", iterations=100_000,
                     eps=((0.0, 0.1), (0.7, 0.01)),
                     sigma=((0.0, 5.0), (0.3, 1.5), (0.7, 1e-5))),
    # the paper's soft winner at width 0.5, eps annealed to 0.001
    "w05-soft": dict(code_width=0.5, winner_rule="soft", iterations=100_000,
                     eps=((0.0, 0.1), (0.7, 0.01), (1.0, 0.001)),
                     sigma=((0.0, 5.0), (0.3, 1.5), (0.7, 1e-5))),
    # the same with 3 refinement rounds whose means take in the neighbours (refine_sigma)
    "w05-soft-sigma07": dict(code_width=0.5, winner_rule="soft", iterations=100_000,
                             eps=((0.0, 0.1), (0.7, 0.01), (1.0, 0.001)),
                             sigma=((0.0, 5.0), (0.3, 1.5), (0.7, 1e-5)),
                             refine_rounds=3, refine_sigma=0.7),
    # twice the rounds
    "w05-soft-sigma07-r6": dict(code_width=0.5, winner_rule="soft", iterations=100_000,
                                eps=((0.0, 0.1), (0.7, 0.01), (1.0, 0.001)),
                                sigma=((0.0, 5.0), (0.3, 1.5), (0.7, 1e-5)),
                                refine_rounds=6, refine_sigma=0.7),
    # the cross-view start on the torus (sigmapi.rules.ordering.torus_angles), sigma capped
    # at ordering_sigma 3, then the winner-only refinement round
    "cv-w05-soft": dict(code_width=0.5, winner_rule="soft", iterations=100_000,
                        eps=((0.0, 0.1), (0.7, 0.01), (1.0, 0.001)),
                        sigma=((0.0, 5.0), (0.3, 1.5), (0.7, 1e-5)), ordering="crossview"),
    # the same with w05-soft-sigma07's 3 neighbourhood rounds
    "cv-w05-soft-sigma07": dict(code_width=0.5, winner_rule="soft", iterations=100_000,
                                eps=((0.0, 0.1), (0.7, 0.01), (1.0, 0.001)),
                                sigma=((0.0, 5.0), (0.3, 1.5), (0.7, 1e-5)),
                                ordering="crossview", refine_rounds=3, refine_sigma=0.7),
    # the same with 6 rounds
    "cv-w05-soft-sigma07-r6": dict(code_width=0.5, winner_rule="soft", iterations=100_000,
                                   eps=((0.0, 0.1), (0.7, 0.01), (1.0, 0.001)),
                                   sigma=((0.0, 5.0), (0.3, 1.5), (0.7, 1e-5)),
                                   ordering="crossview", refine_rounds=6, refine_sigma=0.7),
    # the training's neighbourhood stops at the refinement's 0.7 instead of going to 0
    "cv-w05-soft-floor07": dict(code_width=0.5, winner_rule="soft", iterations=100_000,
                                eps=((0.0, 0.1), (0.7, 0.01), (1.0, 0.001)),
                                sigma=((0.0, 5.0), (0.3, 1.5), (0.7, 0.7)),
                                ordering="crossview", refine_rounds=3, refine_sigma=0.7),
    # cv-w05-soft-floor07 from the paper's random start (the start's share of the result)
    "w05-soft-floor07": dict(code_width=0.5, winner_rule="soft", iterations=100_000,
                             eps=((0.0, 0.1), (0.7, 0.01), (1.0, 0.001)),
                             sigma=((0.0, 5.0), (0.3, 1.5), (0.7, 0.7)),
                             refine_rounds=3, refine_sigma=0.7),
    # paper-2d's rule and schedule at width 1.0 from the cross-view start
    "cv-w10-mind": dict(code_width=1.0, winner_rule="min_distance", iterations=100_000,
                        eps=((0.0, 0.1), (0.7, 0.01)),
                        sigma=((0.0, 5.0), (0.3, 1.5), (0.7, 1e-5)), ordering="crossview"),
}  # fmt: skip
"""The torus variants by name (fields over :data:`BASE`; a variant's own fields win)."""


def config(variant: str, seed: int) -> SOMConfig:
    """The config of ``variant`` at ``seed``."""
    return SOMConfig(**{**BASE, **VARIANTS[variant]}, seed=seed)


def run_seed(variant: str, seed: int) -> dict[str, Any]:
    """One seed: the metrics at the end of the training and after the refinement."""
    cfg = config(variant, seed)
    model = SigmaPiSOM(cfg)
    before: list[dict[str, Any]] = []
    eval_cpu = [0.0]

    def mark(m: SigmaPiSOM) -> None:
        if not before and m.t_ >= cfg.iterations:
            c = time.process_time()
            before.append(evaluate(m).to_dict())
            eval_cpu[0] = time.process_time() - c

    c0 = time.process_time()
    model.fit(callback=mark)
    cpu = time.process_time() - c0 - eval_cpu[0]
    after = evaluate(model).to_dict()

    def pick(r: dict[str, Any]) -> dict[str, Any]:
        return {k: bool(r[k]) if k == "seamless" else float(r[k]) for k in KEYS}

    return {"seed": seed, "cpu_s": round(cpu, 1), "before": pick(before[0]), "after": pick(after)}


def summary(runs: list[dict[str, Any]]) -> dict[str, Any]:
    """Per stage (before, after the refinement): medians, seeds seamless with circular order
    >= 0.95."""
    out: dict[str, Any] = {"seeds": len(runs)}
    for stage in ("before", "after"):
        rows = [r[stage] for r in runs]
        out[stage] = {
            **{k: float(np.median([r[k] for r in rows])) for k in KEYS if k != "seamless"},
            "seamless_and_order_circular_0.95": sum(
                r["seamless"] and r["order_circular"] >= 0.95 for r in rows
            ),
        }
    out["cpu_s_median"] = float(np.median([r["cpu_s"] for r in runs]))
    return out


def write_json(path: Path, data: dict[str, Any]) -> None:
    """Write ``data`` to ``path`` atomically (a temporary file renamed over it)."""
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(data, indent=1) + "\n", encoding="utf-8")
    os.replace(tmp, path)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--variants", default=",".join(VARIANTS))
    parser.add_argument("--seeds", nargs="*", type=int, default=[0, 1, 2])
    parser.add_argument("--out", default=str(ROOT / "results" / "ceiling-torus.json"))
    args = parser.parse_args()
    result: dict[str, Any] = {
        "command": "python benchmarks/bench_torus.py " + " ".join(sys.argv[1:]),
        "machine": f"{platform.machine()}, {os.cpu_count()} cores, shared",
        "variants": {},
    }
    for name in args.variants.split(","):
        runs = []
        for seed in args.seeds:
            runs.append(run_seed(name, seed))
            print(name, json.dumps(runs[-1]), flush=True)
            result["variants"][name] = {
                "config": config(name, 0).replace(seed=None).to_dict(),
                "summary": summary(runs),
                "runs": runs,
            }
            write_json(Path(args.out), result)


if __name__ == "__main__":
    main()
