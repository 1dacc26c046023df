"""Where the refinement's seconds go on the paper-2d map: a CPU profile of its phases.

Usage (from the repository root)::

    python benchmarks/bench_refine_profile.py --seed 509            # trains paper-2d first
    python benchmarks/bench_refine_profile.py --model m.npz         # a trained paper-2d map

Measures, in CPU seconds of this process (all threads) per 1,000 refinement pairs, on the
fast kernel: drawing the pairs (the task's sampler), the winner search of view 0 (blocks of
1,000 pairs as the refinement runs it, and all blocks in one call, sorted together by the
codes' peaks), the accumulation of view 1's outer products and the round's division; and the
winner search at larger ``kernel_tol`` with the share of the reference kernel's winners it
keeps. With ``--seed`` also the training's CPU seconds (``refine_rounds = 0``). Writes
``benchmarks/results/refine-profile.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

import sigmapi
from sigmapi import SigmaPiSOM
from sigmapi.kernels import fast, reference
from sigmapi.rules.refinement import assignment

ROOT = Path(__file__).resolve().parent


def cpu(fn: Callable[[], Any]) -> tuple[float, Any]:
    """CPU seconds of ``fn()`` and its value."""
    c = time.process_time()
    out = fn()
    return time.process_time() - c, out


def profile(model: SigmaPiSOM, blocks: int) -> dict[str, Any]:
    """The phases of one refinement round's first ``blocks`` blocks on ``model``'s map."""
    st, shape, rule = model._state, model.map_shape, model.winner_rule_.hard
    cut = model.config.soft_cut
    n = 1000
    t_sample, batches = cpu(lambda: [model.sampler.sample(n, model._seq(4, 0, b))
                                     for b in range(blocks + 1)])  # fmt: skip
    warm = batches.pop(0)  # compiles what the timed calls use
    fast.winners_of(st, warm.x0[:32], warm.y0[:32], shape, rule, 0.0, cut)

    def search(s: Any) -> list[np.ndarray]:
        return [fast.winners_of(s, b.x0, b.y0, shape, rule, 0.0, cut) for b in batches]

    t_win, winners = cpu(lambda: search(st))
    x0 = np.concatenate([b.x0 for b in batches])
    y0 = np.concatenate([b.y0 for b in batches])
    t_group, grouped = cpu(lambda: fast.winners_of(st, x0, y0, shape, rule, 0.0, cut))
    assert np.array_equal(grouped, np.concatenate(winners))
    acc = fast.refine_start(st)
    jb, pi, pv = st.scratch()[:3]

    def sums() -> None:
        for b, k in zip(batches, winners, strict=True):
            a = np.ascontiguousarray(assignment(k, shape, 0.0, False))
            fast._refine_sums(acc.sums, acc.mass, a, np.ascontiguousarray(b.x1),
                              np.ascontiguousarray(b.y1), st.tol, jb, pi, pv)  # fmt: skip

    t_sums, _ = cpu(sums)
    t_finish, _ = cpu(lambda: fast.refine_finish(st, acc))
    dense = fast.export(st)
    check = batches[:2]
    ref = np.concatenate([reference.winners_of(dense, b.x0, b.y0, shape, rule, 0.0, cut)
                          for b in check])  # fmt: skip
    tols = {}
    for tol in (st.tol, 3e-4, 1e-3):
        s = fast.prepare(dense, tol=tol)
        fast.winners_of(s, warm.x0[:32], warm.y0[:32], shape, rule, 0.0, cut)
        t, got = cpu(lambda s=s: search(s))
        kept = float(np.mean(np.concatenate(got[: len(check)]) == ref))
        tols[f"{tol:g}"] = {"winners_cpu_s_per_1000": t / blocks, "reference_winners_kept": kept}
    per = {
        "sample": t_sample / (blocks + 1),
        "winners": t_win / blocks,
        "winners_all_blocks_in_one_call": t_group / blocks,
        "sums": t_sums / blocks,
        "finish_per_round": t_finish,
    }
    return {
        "cpu_s_per_1000_pairs": per,
        "kernel_tol": tols,
        "reference_check_pairs": int(sum(len(b.x0) for b in check)),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--model", help="a trained paper-2d model file (else --seed trains one)")
    parser.add_argument("--seed", type=int, default=509)
    parser.add_argument("--blocks", type=int, default=20, help="blocks of 1,000 pairs timed")
    parser.add_argument("--out", default=str(ROOT / "results" / "refine-profile.json"))
    args = parser.parse_args()
    result: dict[str, Any] = {
        "command": "python benchmarks/bench_refine_profile.py " + " ".join(sys.argv[1:]),
        "machine": f"{platform.machine()}, {os.cpu_count()} cores, shared",
        "load_avg_1min_start": round(os.getloadavg()[0], 2),
    }
    if args.model:
        model = sigmapi.load(args.model)
    else:
        cfg = sigmapi.load_preset("paper-2d").replace(seed=args.seed, refine_rounds=0)
        t, model = cpu(lambda: SigmaPiSOM(cfg).fit())
        result["training_cpu_s"] = round(t, 2)
    result["iterations"] = model.t_
    result.update(profile(model, args.blocks))
    result["load_avg_1min_end"] = round(os.getloadavg()[0], 2)
    out = Path(args.out)
    tmp = out.with_name(out.name + ".tmp")  # written whole, then renamed over the result
    tmp.write_text(json.dumps(result, indent=1) + "\n", encoding="utf-8")
    os.replace(tmp, out)
    print(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()
