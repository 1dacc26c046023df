"""Where the refinement's seconds go on the paper-2d map: a CPU profile of its phases.

Usage (from the repository root)::

    python benchmarks/bench_refine_profile.py --seed 509            # trains paper-2d first
    python benchmarks/bench_refine_profile.py --model m.npz         # a trained paper-2d map

Measures, in CPU seconds of this process (all threads) per 1,000 refinement pairs, on the
fast kernel: drawing the pairs (the task's sampler, into arrays it reuses, as the refinement
draws them), the refinement's winner search of view 0
(``sigmapi.kernels._refining``: bounds per tile and group, then scores for the units that can win;
``GROUP`` blocks of 1,000 pairs per call, as the refinement calls the kernel) beside the full
search it replaces (``fast.winners_of``), whether the two find the same winners on every timed
pair, the share of the reference kernel's winners kept (2,000 pairs), the hard assignment's
sums of view 1, the round's new weights and the round's search index. With ``--seed`` also
the training's CPU seconds (``refine_rounds = 0``, after the ordered start); ``--whole``:
then the whole round as ``fit`` runs it, and its ratio to the training in the same process;
beside them the machine's triad bandwidth (one thread, ``bench_bandwidth.py``'s), measured at
the end of the run. ``--floors``: what the same arithmetic costs with its weights in cache
(:func:`floors`), beside the stream. Writes ``benchmarks/results/refine-profile.json``.
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
from types import SimpleNamespace
from typing import Any

import numpy as np
from numba import njit

import _common
import sigmapi
from sigmapi import SigmaPiSOM
from sigmapi.kernels import _refining, fast, reference
from sigmapi.kernels._rows import MIN_DISTANCE
from sigmapi.model._refine import GROUP
from sigmapi.model._run import rng

ROOT = Path(__file__).resolve().parent


def cpu(fn: Callable[[], Any]) -> tuple[float, Any]:
    """CPU seconds of ``fn()`` and its value."""
    c = time.process_time()
    out = fn()
    return time.process_time() - c, out


def profile(
    model: SigmaPiSOM, blocks: int, with_floors: bool = False, tol: float = 0.0
) -> dict[str, Any]:
    """The phases of one refinement round's first ``blocks`` blocks on ``model``'s map (and,
    ``with_floors``, :func:`floors` on the first group of them); ``tol``: the refinement's
    ``refine_tol`` (0: the bit-exact path; above 0 the fast path, whose winners are then
    compared with the full search's as a share, not for equality)."""
    st, rule = model._run.state, model.winner_rule_.hard
    geometry = model.config.geometry
    n = 1000
    # as the refinement draws: into memory it reuses (touched before the timing)
    codes = [np.full(((blocks + 1) * n, int(np.prod(s))), np.nan)
             for s in (model.x_shape, model.y_shape) * 2]  # fmt: skip

    def draw(b: int) -> SimpleNamespace:
        at = slice(b * n, (b + 1) * n)
        views = (codes[0][at], codes[1][at], codes[2][at], codes[3][at])
        model.sampler.sample(n, rng(model.seed_entropy, 4, 0, b), out=views, exact=tol == 0)
        return SimpleNamespace(**dict(zip(("x0", "y0", "x1", "y1"), views, strict=True)))

    warm = draw(0)  # compiles (or loads) what the timed calls use
    t_sample, batches = cpu(lambda: [draw(b) for b in range(1, blocks + 1)])
    acc = fast.KERNEL.refine_start(st, tol=tol)
    acc.sums.fill(0.0)  # its pages touched: the round's first touch is not a block's cost
    acc.code_shapes = (model.x_shape, model.y_shape)
    t_index, _ = cpu(
        lambda: fast.KERNEL._refine_winners(st, acc, warm.x0[:32], warm.y0[:32], geometry, rule)
    )
    fast.KERNEL.winners_of(st, warm.x0[:32], warm.y0[:32], geometry, rule, 0.0)
    cut = max(st.tol, acc.tol)  # the sums' cut (the fast path's own above the kernel's)
    _refining.hard_sums(np.zeros_like(acc.sums), np.zeros_like(acc.mass),
                        np.zeros(4, dtype=np.int64), warm.x1[:4], warm.y1[:4], cut)  # fmt: skip

    # as the refinement calls the kernel: GROUP blocks at a time
    batches = [
        SimpleNamespace(**{f: np.concatenate([getattr(b, f) for b in batches[i : i + GROUP]])
                           for f in ("x0", "y0", "x1", "y1")})
        for i in range(0, len(batches), GROUP)
    ]  # fmt: skip
    # the search's work arrays touched, as after a round's first call (a round makes 30 calls
    # into the same memory; two timed calls would count its first page faults 15 times over)
    rows = max(len(b.x0) for b in batches)
    acc.index.work("key", rows, 0, np.int64).fill(0)

    def search() -> list[np.ndarray]:
        return [fast.KERNEL._refine_winners(st, acc, b.x0, b.y0, geometry, rule) for b in batches]

    def full() -> list[np.ndarray]:
        return [fast.KERNEL.winners_of(st, b.x0, b.y0, geometry, rule, 0.0) for b in batches]

    t_win, winners = cpu(search)
    t_full, every = cpu(full)
    same = all(np.array_equal(a, b) for a, b in zip(winners, every, strict=True))

    def sums() -> None:
        for b, k in zip(batches, winners, strict=True):
            _refining.hard_sums(acc.sums, acc.mass, k, np.ascontiguousarray(b.x1),
                                np.ascontiguousarray(b.y1), cut)  # fmt: skip

    t_sums, _ = cpu(sums)
    t_finish, _ = cpu(lambda: fast.KERNEL.refine_finish(st, acc))
    dense = fast.KERNEL.export(st)
    check = [SimpleNamespace(x0=batches[0].x0[:2000], y0=batches[0].y0[:2000])]
    ref = np.concatenate(
        [reference.KERNEL.winners_of(dense, b.x0, b.y0, geometry, rule, 0.0) for b in check]
    )
    per = {
        "sample": t_sample / blocks,
        "winners": t_win / blocks,
        "winners_full_search": t_full / blocks,
        "sums": t_sums / blocks,
        "finish_per_round": t_finish,
        "search_index_per_round": t_index,
    }
    out = {
        "cpu_s_per_1000_pairs": per,
        "winners_equal_to_full_search": same,
        "winners_share_equal_to_full_search": float(
            np.mean(np.concatenate(winners) == np.concatenate(every))
        ),
        "refine_tol": tol,
        "winners_compared": int(blocks * n),
        "reference_winners_kept": float(np.mean(winners[0][:2000] == ref)),
        "reference_check_pairs": int(sum(len(b.x0) for b in check)),
    }
    if with_floors:
        out["floors"] = floors(model, acc, batches[0], winners[0])
    return out


HOT = 16
"""Copies of every pair searched (or added) one after another for the in-cache cost: the first
copy reads the pair's weights from the stream, the other 15 find them in cache."""


@njit(cache=True)
def _passes(raw, scale, sqnorm, rule, x, y, tol, repeats):  # pragma: no cover - compiled
    """CPU work of ``repeats`` exact passes of four units (``_refining._exact``) on one pair,
    its weights in cache after the first; returns the pair's prefiltered grid size."""
    ib = np.empty(x.shape[0], dtype=np.int64)
    jb = np.empty(y.shape[0], dtype=np.int64)
    cand = np.arange(4)
    score = np.empty(4)
    ni, nj, thr = _refining._kept(x, y, tol, ib, jb)
    for _ in range(repeats):
        _refining._exact(raw, scale, sqnorm, rule, cand, 4, x, y, ib, ni, jb, nj, thr, score)
    return ni * nj


def _summed(model: SigmaPiSOM, index: Any, x: np.ndarray, y: np.ndarray, rule: int) -> Any:
    """Per pair of ``x, y``, means: the units whose bound reaches the winner's exact score (the
    fewest any bound-first search must sum), the units the search sums (best bound first, four
    a pass, until no bound left reaches the best), its passes, the kept input pairs and the
    prefilter's grid (what a pass runs over); the exact scores in NumPy (float64, any order:
    enough to count)."""
    st = model._run.state
    k = st.shape[0]
    ub, _ = _bounds(model, index, x, y, rule)
    w = np.asarray(st.raw, dtype=np.float64) * st.scale[None, :]
    need, summed, passes, kept, grid = [], [], [], [], []
    for b in range(x.shape[0]):
        v = np.outer(x[b], y[b]).ravel()
        mx, my = np.abs(x[b]).max(), np.abs(y[b]).max()
        cut = st.tol * mx * my
        keep = np.abs(v) > cut
        grid.append(int(np.sum(np.abs(x[b]) * my > cut) * np.sum(np.abs(y[b]) * mx > cut)))
        h = v[keep] @ w[keep]
        score = 2.0 * h - st.scale**2 * st.sqnorm if rule == MIN_DISTANCE else h
        order = np.argsort(-ub[b], kind="stable")
        best, done, npass = -np.inf, 0, 0
        while done < k and ub[b, order[done]] >= best:
            group = order[done : done + 4]
            group = group[ub[b, group] >= best]
            best = max(best, float(score[group].max()))
            done += len(group)
            npass += 1
        need.append(int(np.sum(ub[b] >= score.max())))
        summed.append(done)
        passes.append(npass)
        kept.append(int(keep.sum()))
    return np.mean(need), np.mean(summed), np.mean(passes), np.mean(kept), np.mean(grid)


@njit(cache=True)
def _unit_bounds(norms, members_x, members_y, c, x, y, tol, rule, ub):  # pragma: no cover
    """Every unit's bound for every pair of ``x, y`` into ``ub``, as the search bounds a unit
    (``_refining._products``, then ``_refining._bounds`` over all units)."""
    n_tx, n_ty = members_x.shape[0], members_y.shape[0]
    xv, yv = np.empty(members_x.shape), np.empty(members_y.shape)
    xt, yt, xs, ys = np.empty(n_tx), np.empty(n_ty), np.empty(n_tx), np.empty(n_ty)
    tl = np.empty(n_tx * n_ty, dtype=np.int64)
    sv = np.empty(n_tx * n_ty, dtype=np.float32)
    width = members_x.shape[1] * members_y.shape[1]
    vb = np.empty((n_tx * n_ty, width), dtype=np.float32)
    xe, ye = np.empty(width), np.empty((n_ty, width))
    s = np.empty(ub.shape[1], dtype=np.float32)
    for b in range(x.shape[0]):
        # left unformatted: the arguments in the rows of the kernel's signature
        n = _refining._products(x[b], y[b], tol, members_x, members_y, xv, yv, xt, yt, xs, ys,
                                xe, ye, tl, sv, vb)  # fmt: skip
        _refining._bounds(norms, tl, sv, n, 0, ub.shape[1], c, rule, s, ub[b])


def _bounds(model: SigmaPiSOM, index: Any, x: np.ndarray, y: np.ndarray, rule: int) -> Any:
    """Every unit's bound ``(B, K)`` for the pairs ``x, y`` as the search computes a unit's
    (the search itself bounds groups first, and units only in the groups that may win), and
    their CPU seconds per 1,000 pairs (the median of three)."""
    st = model._run.state
    ub = np.full((x.shape[0], st.shape[0]), np.nan)  # touched: no page faults in the timing
    c = st.scale * st.scale * st.sqnorm
    times = []
    for _ in range(3):
        # left unformatted: the arguments in the rows of the kernel's signature
        t, _ = cpu(lambda: _unit_bounds(index.norms, index.members_x, index.members_y, c,
                                        np.ascontiguousarray(x), np.ascontiguousarray(y),
                                        float(st.tol), rule, ub))  # fmt: skip
        times.append(t * 1000 / x.shape[0])
    return ub, float(np.median(times))


def floors(model: SigmaPiSOM, acc: Any, batch: SimpleNamespace, won: np.ndarray) -> dict[str, Any]:
    """What the refinement's arithmetic costs with its weights in cache, beside the stream, on
    one call's pairs (``batch``, its winners ``won``): the winner search and the hard sums per
    1,000 pairs in the stream (each pair once, as the round runs) and in cache (each pair
    :data:`HOT` times in a row); one exact pass of four units on one pair in cache, per pass
    and per multiply-add; how many units the search sums per pair (and the fewest any
    bound-first search must), its passes, the kept input pairs and the prefilter's grid per
    pair, and the bounds alone (their norms fit in cache) per 1,000 pairs."""
    st, rule = model._run.state, model.winner_rule_.hard
    geometry, code = model.config.geometry, fast._rule_code(rule)[1]
    n = batch.x0.shape[0]
    hot = np.repeat(np.arange(0, n, HOT), HOT)
    once = (batch.x0, batch.y0, batch.x1, batch.y1, won)
    views = {"stream": once, "in_cache": tuple(a[hot] for a in once)}
    sums, mass = np.zeros_like(acc.sums), np.zeros_like(acc.mass)
    out: dict[str, Any] = {"pairs": n, "copies_in_cache": HOT}
    for name, (x0, y0, x1, y1, k) in views.items():
        search, add = [], []
        for _ in range(3):
            t, _ = cpu(lambda: fast.KERNEL._refine_winners(st, acc, x0, y0, geometry, rule))  # noqa: B023
            search.append(t * 1000 / x0.shape[0])
            t, _ = cpu(lambda: _refining.hard_sums(sums, mass, k, x1, y1, st.tol))  # noqa: B023
            add.append(t * 1000 / x0.shape[0])
        out[f"search_{name}"] = float(np.median(search))
        out[f"sums_{name}"] = float(np.median(add))
    index = acc.index
    x, y = np.ascontiguousarray(batch.x0[0]), np.ascontiguousarray(batch.y0[0])
    _passes(st.raw, index.scale, st.sqnorm, code, x, y, st.tol, 1)
    reps = 20000
    t, grid = cpu(lambda: _passes(st.raw, index.scale, st.sqnorm, code, x, y, st.tol, reps))
    need, summed, passes, kept, grid_mean = _summed(
        model, index, batch.x0[:1000], batch.y0[:1000], code
    )
    _, bounds = _bounds(model, index, batch.x0, batch.y0, code)
    out["exact_pass_of_4_units_in_cache_us"] = t / reps * 1e6
    out["exact_ns_per_step_and_unit_in_cache"] = t / reps / (4 * grid) * 1e9
    out["exact_grid_of_the_pair"] = int(grid)
    out["units_summed_per_pair"] = float(summed)
    out["units_that_must_be_summed_per_pair"] = float(need)
    out["exact_passes_per_pair"] = float(passes)
    out["kept_input_pairs_per_pair"] = float(kept)
    out["prefilter_grid_per_pair"] = float(grid_mean)
    out["bounds_cpu_s_per_1000_pairs"] = float(bounds)
    out["counted_on_pairs"] = 1000
    return out


def whole(model: SigmaPiSOM) -> dict[str, Any]:
    """CPU and wall seconds of the configured refinement on ``model`` (one round of the
    preset's pairs), as ``fit`` runs it."""
    model.config = model.config.replace(refine_rounds=max(model.config.refine_rounds, 1))
    c, w = time.process_time(), time.perf_counter()
    model.refine()
    return {"cpu_s": time.process_time() - c, "wall_s": time.perf_counter() - w,
            "pairs": model.refined_}  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--model", help="a trained paper-2d model file (else --seed trains one)")
    parser.add_argument("--seed", type=int, default=509)
    parser.add_argument("--blocks", type=int, default=20, help="blocks of 1,000 pairs timed")
    parser.add_argument("--whole", action="store_true", help="also run the whole round")
    parser.add_argument("--floors", action="store_true", help="also the costs in cache")
    parser.add_argument("--refine-tol", type=float, default=0.0, help="0: the bit-exact path")
    parser.add_argument("--out", default=str(ROOT / "results" / "refine-profile.json"))
    args = parser.parse_args()
    result: dict[str, Any] = {
        "command": "python benchmarks/bench_refine_profile.py " + " ".join(sys.argv[1:]),
        "machine": f"{platform.machine()}, {os.cpu_count()} cores, shared",
        "load_avg_1min_start": round(os.getloadavg()[0], 2),
    }
    if args.model:
        model = sigmapi.load(args.model)
        model.config = model.config.replace(refine_tol=args.refine_tol)
    else:
        cfg = sigmapi.load_preset("paper-2d").replace(
            seed=args.seed, refine_rounds=0, refine_tol=args.refine_tol
        )
        model = SigmaPiSOM(cfg)
        model.partial_fit(iterations=0)  # the ordered start (and the kernel's numba loads)
        t, _ = cpu(lambda: model.partial_fit(iterations=cfg.iterations))
        result["training_cpu_s"] = round(t, 2)
    result["iterations"] = model.t_
    result.update(profile(model, args.blocks, args.floors, args.refine_tol))
    if args.whole:
        result["whole_round"] = whole(model)
        if "training_cpu_s" in result:
            result["refinement_over_training"] = round(
                result["whole_round"]["cpu_s"] / result["training_cpu_s"], 3
            )
    triad = _common.run_child(ROOT / "bench_bandwidth.py", ["triad", "256"])
    result["triad_one_thread_gb_s"] = round(float(triad["one_thread_gb_s"]), 2)
    result["load_avg_1min_end"] = round(os.getloadavg()[0], 2)
    out = Path(args.out)
    tmp = out.with_name(out.name + ".tmp")  # written whole, then renamed over the result
    tmp.write_text(json.dumps(result, indent=1) + "\n", encoding="utf-8")
    os.replace(tmp, out)
    print(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()
