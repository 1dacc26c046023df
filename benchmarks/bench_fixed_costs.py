"""The two fixed costs of ``sigmapi train --preset paper-2d`` around the training: the
ordered start and the fold check, against an earlier checkout.

Usage (from the repository root)::

    git archive <earlier commit> src | tar -x -C /tmp/before
    python benchmarks/bench_fixed_costs.py --before /tmp/before/src --model m.npz

Every repeat runs, in fresh processes alternating between this checkout and ``--before``
(the earlier checkout's ``src``, first on PYTHONPATH), the command's two steps, each timed
in CPU seconds of the process (``time.process_time``) and in wall seconds, after a
60-iteration run of a 3x3 map of the preset's kind (numba's cache loaded, as
``bench_train_phases.py`` does):

- ``ordered_start``: the model and its iteration-0 weights (the cross-view start,
  ``partial_fit(iterations=0)``) of the preset at ``--seed``;
- ``fold_check``: the command's last step (``sigmapi.cli.train._warn_if_folded``: 4,000 test
  pairs) on the trained model ``--model`` (a paper-2d model file; the same for both).

Medians over ``--repeats``; the load average is written beside them (the wall seconds are
those of a quiet machine only when it is). Writes ``benchmarks/results/fixed-costs.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time
from pathlib import Path
from typing import Any

import _common

ROOT = Path(__file__).resolve().parent
STEPS = ("ordered_start", "fold_check")


def child(preset: str, seed: int, model_file: str) -> dict[str, Any]:
    """One run of both steps, timed (module docstring)."""
    import sigmapi
    from sigmapi.cli.train import _warn_if_folded
    from sigmapi.config import load_preset
    from sigmapi.model.som import SigmaPiSOM, load_model

    cfg = load_preset(preset).replace(seed=seed)
    tiny = cfg.replace(map_shape=(3, 3), x_shape=(4, 4), y_shape=(4, 4), iterations=60,
                       refine_pairs=300)  # fmt: skip
    SigmaPiSOM(tiny).fit()
    trained = load_model(model_file)
    out: dict[str, Any] = {"source": str(Path(sigmapi.__file__).parents[1])}
    for name, step in (
        ("ordered_start", lambda: SigmaPiSOM(cfg).partial_fit(iterations=0)),
        ("fold_check", lambda: _warn_if_folded(trained)),
    ):
        c, w = time.process_time(), time.perf_counter()
        step()
        out[name] = {"cpu_s": time.process_time() - c, "wall_s": time.perf_counter() - w}
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--child", nargs=3, help=argparse.SUPPRESS)
    parser.add_argument("--before", required=False, help="the earlier checkout's src")
    parser.add_argument("--model", help="a trained paper-2d model file")
    parser.add_argument("--preset", default="paper-2d")
    parser.add_argument("--seed", type=int, default=509)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--out", default=str(ROOT / "results" / "fixed-costs.json"))
    args = parser.parse_args()
    if args.child:
        print(json.dumps(child(args.child[0], int(args.child[1]), args.child[2])))
        return
    if not args.before or not args.model:
        parser.error("--before and --model are needed")
    here = ROOT.parent / "src"
    sources = {"this": here, "before": Path(args.before)}
    runs: dict[str, list[dict[str, Any]]] = {k: [] for k in sources}
    loads = []
    for _ in range(args.repeats):
        for key, src in sources.items():
            child_args = [args.preset, str(args.seed), str(Path(args.model).resolve())]
            runs[key].append(_common.run_child(__file__, child_args, src=src))
            loads.append(os.getloadavg()[0])
    med = {
        key: {
            step: {u: round(statistics.median(r[step][u] for r in rs), 3) for u in rs[0][step]}
            for step in STEPS
        }
        for key, rs in runs.items()
    }
    result: dict[str, Any] = {
        "command": "python benchmarks/bench_fixed_costs.py " + " ".join(sys.argv[1:]),
        "preset": args.preset,
        "seed": args.seed,
        "median": med,
        "runs": runs,
        "load_average_1min_per_run": [round(x, 2) for x in loads],
        "machine": _common.machine(),
    }
    _common.write_result(Path(args.out), result)
    print(json.dumps(med, indent=1))


if __name__ == "__main__":
    main()
