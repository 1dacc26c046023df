"""The refinement's fast path (``refine_tol > 0``) against the bit-exact one on paper-2d maps.

Usage (from the repository root)::

    python benchmarks/bench_refine_fast.py --seeds 0 1 2 3 4 --refine-tol 1e-3

Per seed, in one process: the preset trained without refinement (the ordered start untimed,
then the training in CPU seconds of the process, all threads); then one refinement round of
the preset's pairs on copies of that map, the bit-exact path (``refine_tol = 0``) and the fast
path alternating, ``--repeats`` times each, in CPU seconds (medians); the two refined maps'
view consistency and z error (``sigmapi.evaluate``, 10,000 test pairs) and the share of
pairs on which the fast path's winner (its codes, cut and search) equals the bit-exact path's
(the unrefined map, ``--pairs`` fresh pairs). Writes
``benchmarks/results/refine-fast.json``.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

import _common
import sigmapi
from sigmapi import SigmaPiSOM
from sigmapi.kernels import fast
from sigmapi.metrics import evaluate

ROOT = Path(__file__).resolve().parent


def _round(path: Path, tol: float) -> tuple[float, SigmaPiSOM]:
    """CPU seconds of one refinement round at ``refine_tol = tol`` on the map in ``path``."""
    model = sigmapi.load(path)
    model.config = model.config.replace(refine_rounds=1, refine_tol=tol)
    c = time.process_time()
    model.refine()
    return time.process_time() - c, model


def winners_share(model: SigmaPiSOM, tol: float, pairs: int, seed: int) -> float:
    """The share of ``pairs`` fresh pairs whose winner on ``model``'s map is the same on the
    fast path (codes within rounding, its own cut, float32 scores) as on the bit-exact one."""
    st, rule, geometry = model._run.state, model.winner_rule_.hard, model.config.geometry
    exact = model.sampler.sample(pairs, np.random.default_rng([seed, 47]))
    quick = model.sampler.sample(pairs, np.random.default_rng([seed, 47]), exact=False)
    acc = fast.KERNEL.refine_start(st, tol=tol)
    acc.code_shapes = (model.x_shape, model.y_shape)
    got = fast.KERNEL._refine_winners(st, acc, quick.x0, quick.y0, geometry, rule)
    want = fast.KERNEL.winners_of(st, exact.x0, exact.y0, geometry, rule, 0.0)
    return float(np.mean(got == want))


def warm(tol: float) -> None:
    """Load (or compile) what both paths call, on a small 2-D map."""
    tiny = sigmapi.load_preset("paper-2d").replace(
        map_shape=(3, 3), x_shape=(6, 6), y_shape=(6, 6), iterations=60, refine_rounds=1,
        refine_pairs=300, ordering="none", seed=0,
    )  # fmt: skip
    for t in (0.0, tol):
        SigmaPiSOM(tiny.replace(refine_tol=t)).fit()


def one_seed(seed: int, tol: float, repeats: int, pairs: int, tmp: Path) -> dict[str, Any]:
    """Training, both paths' rounds, their maps and winners on one seed."""
    cfg = sigmapi.load_preset("paper-2d").replace(seed=seed, refine_rounds=0)
    model = SigmaPiSOM(cfg)
    model.partial_fit(iterations=0)  # the ordered start
    c = time.process_time()
    model.partial_fit(iterations=cfg.iterations)
    training = time.process_time() - c
    path = model.save(tmp / f"m{seed}.npz")
    share = winners_share(model, tol, pairs, seed)
    times: dict[str, list[float]] = {"exact": [], "fast": []}
    maps: dict[str, Any] = {}
    for _ in range(repeats):
        for name, t in (("exact", 0.0), ("fast", tol)):
            cpu, refined = _round(path, t)
            times[name].append(cpu)
            maps.setdefault(name, refined)
    metrics = {}
    for name, refined in maps.items():
        ev = evaluate(refined)
        metrics[name] = {"view_consistency": ev.view_consistency, "z_error": ev.z_error}
    med = {n: float(np.median(v)) for n, v in times.items()}
    return {
        "seed": seed,
        "training_cpu_s": training,
        "round_cpu_s": times,
        "round_cpu_s_median": med,
        "exact_over_fast": med["exact"] / med["fast"],
        "round_over_training": {n: v / training for n, v in med.items()},
        "maps": metrics,
        "view_consistency_fast_minus_exact": metrics["fast"]["view_consistency"]
        - metrics["exact"]["view_consistency"],
        "z_error_fast_minus_exact": metrics["fast"]["z_error"] - metrics["exact"]["z_error"],
        "winners_equal_share": share,
        "winners_compared": pairs,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3, 4])
    parser.add_argument("--refine-tol", type=float, default=1e-3)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--pairs", type=int, default=20_000)
    parser.add_argument("--out", type=Path, default=ROOT / "results" / "refine-fast.json")
    args = parser.parse_args()
    warm(args.refine_tol)
    seeds = []
    with tempfile.TemporaryDirectory() as tmp:
        for seed in args.seeds:
            seeds.append(one_seed(seed, args.refine_tol, args.repeats, args.pairs, Path(tmp)))
            print(seeds[-1], flush=True)
    ratio = [s["exact_over_fast"] for s in seeds]
    result = {
        "command": "python benchmarks/bench_refine_fast.py " + " ".join(sys.argv[1:]),
        "refine_tol": args.refine_tol,
        "exact_over_fast_median": float(np.median(ratio)),
        "exact_over_fast_worst": float(np.min(ratio)),
        "round_over_training_median": {
            n: float(np.median([s["round_over_training"][n] for s in seeds]))
            for n in ("exact", "fast")
        },
        "largest_view_consistency_difference": max(
            abs(s["view_consistency_fast_minus_exact"]) for s in seeds
        ),
        "largest_z_error_difference": max(abs(s["z_error_fast_minus_exact"]) for s in seeds),
        "least_winners_equal_share": min(s["winners_equal_share"] for s in seeds),
        "seeds": seeds,
        "machine": _common.machine(),
    }
    _common.write_result(args.out, result)


if __name__ == "__main__":
    main()
