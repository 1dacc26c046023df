"""How well D dendritic branches per unit can do when the partition is the Sigma-Pi map's.

For each seed: the Sigma-Pi map of the preset (``sigmapi.SigmaPiSOM(...).fit()``); then, per
branch count D, a dendritic map (``sigmapi.neurons.dendritic.DendriticMap``) whose branches are
set by the batch form of its own rule (each branch the mean of the view-1 pairs assigned to
it) while the *Sigma-Pi map* picks the winner from view 0 (6 steps of 50,000 pairs), then 2
more steps with its own winners. Scored by ``sigmapi.evaluate``. This separates what D
branches can represent from what the two-view rule finds from its own start:

    python benchmarks/bench_neurons_capacity.py --seeds 100 101 102 103 104

writes ``benchmarks/results/neurons-capacity.json``.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from _common import machine, write_result
from sigmapi import SigmaPiSOM, evaluate, load_preset
from sigmapi.neurons.dendritic import DendriticMap
from sigmapi.neurons.training import TrainingConfig

OUT = Path(__file__).resolve().parent / "results" / "neurons-capacity.json"


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seeds", type=int, nargs="+", default=[100, 101, 102, 103, 104])
    p.add_argument("--branches", type=int, nargs="+", default=[4, 7, 10, 15, 30])
    p.add_argument("--preset", default="paper-1d")
    args = p.parse_args()
    cfg = load_preset(args.preset)
    start, cpu = time.perf_counter(), time.process_time()
    rows = []
    for seed in args.seeds:
        sp = SigmaPiSOM(cfg, seed=seed).fit()
        ref = evaluate(sp, n_test=5000).view_consistency
        rng = np.random.default_rng(seed)
        for d in args.branches:
            m = DendriticMap(cfg, d).fit(TrainingConfig(pairs=0, refine_rounds=0), seed=seed)
            for teacher in [sp] * 6 + [m] * 2:
                b = m.sampler.sample(50_000, rng)
                m.refine(teacher.winner(b.x0, b.y0), b.x1, b.y1)
            e = evaluate(m, n_test=5000)
            rows.append({"seed": seed, "branches": d, "synapses": m.synapses,
                         "sigma_pi_view_consistency": ref,
                         "view_consistency": e.view_consistency, "order_r2": e.order_r2,
                         "z_error": e.z_error, "folded": bool(e.folded)})  # fmt: skip
            print(rows[-1], flush=True)
    summary = []
    for d in args.branches:
        gap = [r["view_consistency"] - r["sigma_pi_view_consistency"] for r in rows
               if r["branches"] == d]  # fmt: skip
        near = sum(g >= -0.02 for g in gap)
        summary.append({"branches": d, "vc_gap_median": float(np.median(gap)),
                        "vc_gap_worst": float(min(gap)), "within_002": int(near)})  # fmt: skip
    seeds = " ".join(map(str, args.seeds))
    command = f"python benchmarks/bench_neurons_capacity.py --seeds {seeds}"
    write_result(OUT, {"command": command, "preset": args.preset, "seeds": args.seeds,
                       "rows": rows,
                       "summary": summary, "wall_s": time.perf_counter() - start,
                       "cpu_s": time.process_time() - cpu, "machine": machine()})  # fmt: skip


if __name__ == "__main__":
    main()
