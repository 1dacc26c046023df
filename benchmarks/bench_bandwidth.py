"""Training against the machine's memory bandwidth: bytes moved per iteration, share of a
STREAM-like triad measured in the same run, iterations/s beside the dense reference.

Usage (from the repository root)::

    python benchmarks/bench_bandwidth.py                  # ~10 min on 2 loaded cores
    python benchmarks/bench_bandwidth.py --presets paper-2d --repeats 1

Writes ``benchmarks/results/bandwidth.json``. Every measurement runs in a fresh process, the
variants alternating (``--repeats`` rounds, medians), so all see the same machine load.

- ``triad``: ``a = b + s c`` over three float64 arrays of ``--triad-mib`` MiB each (larger than
  the last-level cache), best of 5, counted as STREAM counts it (24 bytes per element, no
  write-allocate); one thread (training runs on one) and all numba threads.
- ``windows``: the fast kernel's speed at ``--windows`` evenly spaced points of the preset's
  schedule (``--window`` iterations each, seed 0, from the run's ordered start: speed depends on
  the schedule and the data, not on the weights' values). For each window the traffic is
  counted from the run itself (the kept input pairs of both views, the winners, the
  neighbourhood range, the scale folds): every 64-byte line of the weights an iteration reads,
  written lines twice (read and write back). That counts each line once per iteration, so it
  is what the iteration moves if nothing stays in cache between iterations.
- ``run``: the windows combined into a whole run (each window stands for ``1 / windows`` of
  it): estimated seconds, iterations/s, bytes per iteration and the share of the one-thread
  triad bandwidth.
- variants: ``fast`` (as shipped), ``fast-noprefetch`` (``TRAIN_PREFETCH_AHEAD = 0``, the
  kernel before prefetching), ``fast-threads`` (``threads = true``); ``reference``: the dense
  kernel on the first ``--ref-iters`` iterations.
- ``--baseline-src``: the variant ``baseline``, the fast kernel of another checkout's ``src``
  (e.g. the commit before a kernel change), measured the same way, alternating with the
  others; ``gain_over_baseline`` is ``fast``'s iterations/s over its.
- ``c_simulator_it_per_s``: the authors' C simulator at paper-2d, 11.1 it/s, *measured
  earlier* on this machine (issue 12: rebuilt here, alternating runs), not in this run.
"""

from __future__ import annotations

import argparse
import functools
import statistics
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

import _common

ROOT = Path(__file__).resolve().parent
C_SIMULATOR_IT_PER_S = {"paper-2d": 11.1}
"""The authors' C simulator at paper-2d, measured earlier (issue 12), not in this run."""
VARIANTS = ("fast", "fast-noprefetch", "fast-threads")
LINE = 64


# ---------------------------------------------------------------------------- children


def child_triad(mib: int) -> dict[str, Any]:
    """STREAM triad bandwidth (GB/s), one thread and all numba threads."""
    import numba
    from numba import njit, prange

    @njit(cache=False)
    def triad(a, b, c, s):  # type: ignore[no-untyped-def]
        for i in range(a.shape[0]):
            a[i] = b[i] + s * c[i]

    @njit(cache=False, parallel=True)
    def triad_par(a, b, c, s):  # type: ignore[no-untyped-def]
        for i in prange(a.shape[0]):
            a[i] = b[i] + s * c[i]

    n = mib * 2**20 // 8
    a, b, c = np.zeros(n), np.ones(n), np.full(n, 2.0)
    out: dict[str, Any] = {"array_mib": mib, "threads": numba.get_num_threads()}
    for name, f in (("one_thread_gb_s", triad), ("all_threads_gb_s", triad_par)):
        f(a, b, c, 3.0)
        best = min(_timed(f, a, b, c, 3.0) for _ in range(5))
        out[name] = 24 * n / best / 1e9
    return out


def _timed(f: Any, *args: Any) -> float:
    t0 = time.perf_counter()
    f(*args)
    return time.perf_counter() - t0


def child_windows(preset: str, variant: str, windows: int, window: int) -> dict[str, Any]:
    """Speed and traffic of the fast kernel at ``windows`` points of ``preset``'s schedule."""
    from sigmapi import SigmaPiSOM, load_preset
    from sigmapi.kernels import fast
    from sigmapi.model.som import BLOCK

    if variant == "fast-noprefetch":
        fast.TRAIN_PREFETCH_AHEAD = 0
    cfg = load_preset(preset).replace(backend="fast", seed=0, threads=variant == "fast-threads")
    model = SigmaPiSOM(cfg)
    try:  # the ordered start; loads (or compiles) the kernel
        model.fit(iterations=20)
    except TypeError:  # --baseline-src: a checkout from before fit(views, *, iterations)
        model.fit(20)
    # the kernel's own state: the benchmark reads its scales (a --baseline-src of before the
    # run state held it in model._state)
    state: Any = model._run.state if hasattr(model, "_run") else model._state
    rule = {"winner_rule": cfg.winner_rule, "threads": cfg.threads}
    if hasattr(fast, "KERNEL"):
        train = functools.partial(fast.KERNEL.train_block, geometry=cfg.geometry, **rule)
    else:  # --baseline-src: a checkout from before the kernel classes (the map as loose args)
        train = functools.partial(
            fast.train_block, map_shape=cfg.map_shape, soft_cut=cfg.soft_cut, **rule
        )
    out = []
    for w in range(windows):
        t = int((w + 0.5) / windows * cfg.iterations) // BLOCK * BLOCK
        b = model.training_block(t // BLOCK)
        n = min(window, BLOCK)
        ts = np.arange(t, t + n)
        data = (b.x0[:n], b.y0[:n], b.x1[:n], b.y1[:n])
        sig, eps = model.sigma_at(ts), model.eps_at(ts)
        scale0 = state.scale.copy()
        t0 = time.perf_counter()
        won = train(state, *data, sig, eps)
        dt = time.perf_counter() - t0
        moved = traffic(state, cfg, data, won, sig, eps, scale0)
        out.append({"t": t, "iterations": n, "seconds": dt, "it_per_s": n / dt, **moved})
    return {"preset": preset, "variant": variant, "windows": out}


def child_reference(preset: str, n_iter: int) -> dict[str, Any]:
    """Iterations/s of the dense reference kernel on the first ``n_iter`` iterations."""
    from sigmapi import SigmaPiSOM, load_preset

    model = SigmaPiSOM(load_preset(preset).replace(backend="reference", seed=0))
    model.fit(iterations=2)
    t0 = time.perf_counter()
    model.partial_fit(iterations=n_iter)
    return {"iterations": n_iter, "it_per_s": n_iter / (time.perf_counter() - t0)}


# ---------------------------------------------------------------------------- traffic


def _lines(start: np.ndarray, stop: np.ndarray) -> np.ndarray:
    """Cache lines holding bytes ``[start, stop)`` (elementwise; 0 where empty)."""
    return np.where(stop > start, (stop - 1) // LINE - start // LINE + 1, 0)


def traffic(
    state: Any,
    cfg: Any,
    data: tuple[np.ndarray, ...],
    won: np.ndarray,
    sig: np.ndarray,
    eps: np.ndarray,
    scale0: np.ndarray,
) -> dict[str, float]:
    """Bytes of weights one iteration touches, mean over the window (see the module doc)."""
    from sigmapi.codes import grid_coordinates
    from sigmapi.kernels import fast

    k_units = state.raw.shape[1]
    n_pairs = state.raw.shape[0]
    item = state.raw.dtype.itemsize
    tol = state.tol
    coords = grid_coordinates(tuple(cfg.map_shape))
    x0, y0, x1, y1 = data
    act = upd = fold = 0
    scale = scale0.copy()
    for t in range(x0.shape[0]):
        # activation of view 0 (the kernel computes the next iteration's during this one)
        p0 = _kept(x0[t], y0[t], tol)
        act += int(_lines(p0 * k_units * item, (p0 + 1) * k_units * item).sum())
        # neighbourhood of the winner: the flat unit range [lo, hi) the update sweeps
        d2 = ((coords - coords[won[t]]) ** 2).sum(axis=1)
        a = np.exp(-d2 / (2.0 * sig[t] ** 2))
        a /= np.linalg.norm(a)
        ea = eps[t] * a
        keep = np.flatnonzero(ea > tol * ea.max())
        lo, hi = int(keep.min()), int(keep.max()) + 1
        p1 = _kept(x1[t], y1[t], tol)
        base = p1 * k_units * item
        upd += 2 * int(_lines(base + lo * item, base + hi * item).sum())
        # scale folds: a unit whose scale falls below RENORM rewrites its column
        scale = scale * (1.0 - ea)
        folds = scale < fast.RENORM
        fold += 2 * int(folds.sum()) * n_pairs
        scale[folds] = 1.0
    n = x0.shape[0]
    return {
        "bytes_activation": LINE * act / n,
        "bytes_update": LINE * upd / n,
        "bytes_folds": LINE * fold / n,
        "bytes_per_iteration": LINE * (act + upd + fold) / n,
    }


def _kept(x: np.ndarray, y: np.ndarray, tol: float) -> np.ndarray:
    """Flat indices ``i * n_y + j`` of the pairs the fast kernel keeps (its ``_pairs``)."""
    v = np.abs(np.outer(x, y)).ravel()
    return np.flatnonzero(v > tol * np.abs(x).max() * np.abs(y).max())


def child_main(argv: list[str]) -> dict[str, Any]:
    kind = argv[0]
    if kind == "triad":
        return child_triad(int(argv[1]))
    if kind == "reference":
        return child_reference(argv[1], int(argv[2]))
    return child_windows(argv[1], argv[2], int(argv[3]), int(argv[4]))


# ---------------------------------------------------------------------------- driver


def combine(windows: list[dict[str, Any]], iterations: int, bandwidth: float) -> dict[str, Any]:
    """A whole run from its windows (each stands for an equal share of the run)."""
    share = iterations / len(windows)
    seconds = sum(share / w["it_per_s"] for w in windows)
    moved = sum(share * w["bytes_per_iteration"] for w in windows)
    return {
        "seconds_estimated": seconds,
        "it_per_s": iterations / seconds,
        "bytes_per_iteration": moved / iterations,
        "gb_per_s": moved / seconds / 1e9,
        "share_of_one_thread_triad": moved / seconds / 1e9 / bandwidth,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--presets", nargs="*", default=["paper-1d", "paper-2d"])
    parser.add_argument("--repeats", type=int, default=3, help="rounds of every variant")
    parser.add_argument("--windows", type=int, default=10, help="points of the schedule")
    parser.add_argument("--window", type=int, default=500, help="iterations per point")
    parser.add_argument("--ref-iters", type=int, default=100, help="dense reference iterations")
    parser.add_argument("--triad-mib", type=int, default=512)
    parser.add_argument("--out", type=Path, default=ROOT / "results" / "bandwidth.json")
    parser.add_argument("--baseline-src", type=Path, help="another checkout's src to compare")
    parser.add_argument("--baseline-label", help="what the baseline is (default: its git commit)")
    args = parser.parse_args()
    variants = VARIANTS if args.baseline_src is None else (*VARIANTS, "baseline")

    triads: list[dict[str, Any]] = []
    rounds: dict[str, dict[str, list[Any]]] = {p: {v: [] for v in variants} for p in args.presets}
    refs: dict[str, list[float]] = {p: [] for p in args.presets}
    for r in range(args.repeats):
        triads.append(_common.run_child(__file__, ["triad", str(args.triad_mib)]))
        print(f"round {r} triad: {triads[-1]}", flush=True)
        for preset in args.presets:
            for v in variants:
                win = [str(args.windows), str(args.window)]
                src = args.baseline_src.resolve() if v == "baseline" else None
                args_v = ["windows", preset, "fast" if v == "baseline" else v, *win]
                res = _common.run_child(__file__, args_v, src=src)
                rounds[preset][v].append(res["windows"])
                ips = statistics.median(w["it_per_s"] for w in res["windows"])
                print(f"round {r} {preset} {v}: median window {ips:.0f} it/s", flush=True)
            ref = _common.run_child(__file__, ["reference", preset, str(args.ref_iters)])
            refs[preset].append(ref["it_per_s"])
    bw = statistics.median(t["one_thread_gb_s"] for t in triads)

    from sigmapi import load_preset

    presets: dict[str, Any] = {}
    for preset in args.presets:
        iterations = load_preset(preset).iterations
        per_variant = {}
        for v, runs in rounds[preset].items():
            combined = [combine(w, iterations, bw) for w in runs]
            per_variant[v] = {k: statistics.median(c[k] for c in combined) for k in combined[0]} | {
                "windows_first_round": runs[0]
            }
        ref_ips = statistics.median(refs[preset])
        presets[preset] = {
            "iterations": iterations,
            "variants": per_variant,
            "reference_it_per_s": ref_ips,
            "fast_over_reference": per_variant["fast"]["it_per_s"] / ref_ips,
            "prefetch_gain": per_variant["fast"]["it_per_s"]
            / per_variant["fast-noprefetch"]["it_per_s"],
            "c_simulator_it_per_s_measured_earlier": C_SIMULATOR_IT_PER_S.get(preset),
        }
        if "baseline" in per_variant:
            presets[preset]["gain_over_baseline"] = (
                per_variant["fast"]["it_per_s"] / per_variant["baseline"]["it_per_s"]
            )
        print(f"{preset}: {presets[preset]['variants']['fast']}", flush=True)
    import numba

    _common.write_result(
        args.out,
        {
            "command": " ".join(["python benchmarks/bench_bandwidth.py", *sys.argv[1:]]),
            "machine": _common.machine(numba_threads=numba.get_num_threads()),
            "triad": {
                "one_thread_gb_s": bw,
                "all_threads_gb_s": statistics.median(t["all_threads_gb_s"] for t in triads),
                "rounds": triads,
            },
            "presets": presets,
            "baseline": args.baseline_label or _common.commit(args.baseline_src),
        },
    )


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "--child":
        import json

        print(json.dumps(child_main(sys.argv[2:])))
    else:
        main()
