"""A whole refinement round of a trained paper-2d map, this checkout against another one.

Usage (from the repository root)::

    sigmapi train --preset paper-2d --seed 509 --set refine_rounds=0 --out /tmp/m509.npz
    git archive COMMIT src | tar -x -C /tmp/old        # the code before a change
    python benchmarks/bench_refine_compare.py --model /tmp/m509.npz --baseline-src /tmp/old/src

Each measurement runs in a fresh process (the two code bases alternating, ``--repeats``
rounds): numba's functions are loaded (or compiled) by a small run of the same kind first,
untimed; then one round of the model's preset (``refine_pairs`` pairs, at least one round) in
CPU seconds of the process (all threads) and wall seconds, and a SHA-256 of the new weights
(equal digests: the same weights, bit for bit). Writes
``benchmarks/results/refine-compare.json``: medians, the baseline's CPU seconds over this
checkout's, the digests.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import statistics
import sys
import time
from pathlib import Path
from typing import Any

import _common

ROOT = Path(__file__).resolve().parent
SRC = ROOT.parent / "src"


def child(model_path: str) -> dict[str, Any]:
    """One whole round on the ``sigmapi`` first on ``sys.path``."""
    import numpy as np

    import sigmapi
    from sigmapi import SigmaPiSOM

    model = sigmapi.load(model_path)
    tiny = model.config.replace(map_shape=(3, 3), x_shape=(4, 4), y_shape=(4, 4),
                                iterations=60, refine_rounds=1, refine_pairs=300)  # fmt: skip
    SigmaPiSOM(tiny).fit()  # loads (or compiles) what the round calls
    model.config = model.config.replace(refine_rounds=max(1, model.config.refine_rounds))
    c, w = time.process_time(), time.perf_counter()
    model.refine()
    cpu, wall = time.process_time() - c, time.perf_counter() - w
    weights = np.ascontiguousarray(model.weights_)
    return {"cpu_s": cpu, "wall_s": wall, "pairs": model.refined_,
            "sha256": hashlib.sha256(weights.tobytes()).hexdigest()}  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--child", help=argparse.SUPPRESS)
    parser.add_argument("--model", help="a trained paper-2d model (refine_rounds = 0)")
    parser.add_argument("--baseline-src", type=Path, required="--child" not in sys.argv)
    parser.add_argument("--baseline-label", help="what the baseline is (default: its path)")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--out", type=Path, default=ROOT / "results" / "refine-compare.json")
    args = parser.parse_args()
    if args.child:
        print(json.dumps(child(args.child)))
        return
    runs: dict[str, list[dict[str, Any]]] = {"this": [], "baseline": []}
    for _ in range(args.repeats):
        for name, src in (("baseline", args.baseline_src.resolve()), ("this", SRC)):
            runs[name].append(_common.run_child(__file__, [args.model], src))
            print(name, runs[name][-1], flush=True)
    med = {n: {k: statistics.median(r[k] for r in rs) for k in ("cpu_s", "wall_s")}
           for n, rs in runs.items()}  # fmt: skip
    digests = {n: sorted({r["sha256"] for r in rs}) for n, rs in runs.items()}
    result = {
        "command": "python benchmarks/bench_refine_compare.py " + " ".join(sys.argv[1:]),
        "baseline": args.baseline_label or str(args.baseline_src),
        "medians": med,
        "baseline_cpu_over_this": med["baseline"]["cpu_s"] / med["this"]["cpu_s"],
        "baseline_wall_over_this": med["baseline"]["wall_s"] / med["this"]["wall_s"],
        "same_weights": digests["this"] == digests["baseline"] and len(digests["this"]) == 1,
        "digests": digests,
        "runs": runs,
        "machine": _common.machine(),
    }
    _common.write_result(args.out, result)


if __name__ == "__main__":
    main()
