"""How a refinement round draws its pairs (``refine_draw``): random against quasi-random.

Usage (from the repository root)::

    python benchmarks/bench_refine_draw.py --seeds 0 1 2 --pairs 300000 --repeats 3

Part one, per seed, in one process: ``paper-2d`` trained without refinement, then one round
of ``--pairs`` pairs on copies of that map with ``refine_draw = "random"`` and ``"quasi"``
alternating ``--repeats`` times (process CPU seconds, both threads; medians) and both refined
maps scored (:func:`sigmapi.evaluate`, 10,000 test pairs). Part two: the whole command
``sigmapi train --preset paper-2d --seed S`` with each draw (``--set refine_draw=...``),
alternating ``--repeats`` times, its CPU seconds (the child's user + system) and wall
seconds. Writes ``benchmarks/results/refine-draw.json``.
"""

from __future__ import annotations

import argparse
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import _common
import sigmapi
from sigmapi import SigmaPiSOM
from sigmapi.metrics import evaluate

ROOT = Path(__file__).resolve().parent
DRAWS = ("random", "quasi")


def _round(path: Path, draw: str, pairs: int) -> tuple[float, SigmaPiSOM]:
    """CPU seconds of one round of ``pairs`` pairs drawn ``draw`` on the map in ``path``."""
    model = sigmapi.load(path)
    model.config = model.config.replace(refine_rounds=1, refine_pairs=pairs, refine_draw=draw)
    c = time.process_time()
    model.refine()
    return time.process_time() - c, model


def rounds(seed: int, pairs: int, repeats: int, tmp: Path) -> dict[str, Any]:
    """Both draws' rounds on one trained map: CPU seconds and the refined maps' scores."""
    model = SigmaPiSOM(sigmapi.load_preset("paper-2d").replace(seed=seed, refine_rounds=0))
    path = model.fit().save(tmp / f"m{seed}.npz")
    cpu: dict[str, list[float]] = {d: [] for d in DRAWS}
    maps: dict[str, dict[str, float]] = {}
    for _ in range(repeats):
        for draw in DRAWS:
            s, refined = _round(path, draw, pairs)
            cpu[draw].append(s)
            m = evaluate(refined)
            maps[draw] = {"view_consistency": m.view_consistency, "z_error": m.z_error}
    return {
        "seed": seed,
        "round_cpu_s": cpu,
        "round_cpu_s_median": {d: statistics.median(v) for d, v in cpu.items()},
        "maps": maps,
        "view_consistency_quasi_minus_random": maps["quasi"]["view_consistency"]
        - maps["random"]["view_consistency"],
    }


def command(seed: int, draw: str, out: Path) -> dict[str, float]:
    """The whole ``sigmapi train --preset paper-2d`` with ``draw``: the child's CPU and wall."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t = time.perf_counter()
    cmd = [sys.executable, "-m", "sigmapi.cli", "train", "--preset", "paper-2d",
           "--seed", str(seed), "--set", f"refine_draw={draw}", "--out", str(out), "--force",
           "--quiet"]  # fmt: skip
    subprocess.run(cmd, check=True, capture_output=True)
    wall = time.perf_counter() - t
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return {"cpu_s": cpu, "wall_s": wall}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", nargs="*", type=int, default=[0, 1, 2])
    parser.add_argument("--pairs", type=int, default=300_000)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--out", default=str(ROOT / "results" / "refine-draw.json"))
    args = parser.parse_args()
    result: dict[str, Any] = {"command": "python benchmarks/bench_refine_draw.py " +
                              " ".join(sys.argv[1:]), "seeds": []}  # fmt: skip
    with tempfile.TemporaryDirectory() as tmp:
        for seed in args.seeds:
            row = rounds(seed, args.pairs, args.repeats, Path(tmp))
            print(row, flush=True)
            result["seeds"].append(row)
        whole: dict[str, list[dict[str, float]]] = {d: [] for d in DRAWS}
        for _ in range(args.repeats):
            for draw in DRAWS:
                whole[draw].append(command(args.seeds[0], draw, Path(tmp) / "w.npz"))
    result["whole_command"] = {
        "seed": args.seeds[0],
        "runs": whole,
        "cpu_s_median": {d: statistics.median(r["cpu_s"] for r in v) for d, v in whole.items()},
        "wall_s_median": {d: statistics.median(r["wall_s"] for r in v) for d, v in whole.items()},
    }
    gains = [r["view_consistency_quasi_minus_random"] for r in result["seeds"]]
    result["view_consistency_gain_median"] = statistics.median(gains)
    result["round_cpu_quasi_over_random_median"] = statistics.median(
        r["round_cpu_s_median"]["quasi"] / r["round_cpu_s_median"]["random"]
        for r in result["seeds"]
    )
    result["machine"] = _common.machine()
    _common.write_result(Path(args.out), result)
    print(result["whole_command"], result["view_consistency_gain_median"])


if __name__ == "__main__":
    main()
