"""Where the CPU seconds of ``sigmapi train --preset paper-2d`` go: the command in phases.

Usage (from the repository root)::

    python benchmarks/bench_train_phases.py                    # 3 repeats, ~3 min quiet
    python benchmarks/bench_train_phases.py --repeats 1 --cli  # also the real command once

Every repeat runs in a fresh process (so start-up and the numba cache load are those of a
command) the steps of ``sigmapi train`` (``sigmapi.cli.train``) one after another, each timed
in CPU seconds of the process (all threads, ``time.process_time``):

- ``startup``: the interpreter, ``import sigmapi.cli`` and the config (from the process's
  start, ``resource.getrusage``);
- ``numba_load``: the compiled functions the run uses, loaded from numba's cache (compiled on a
  first run): a 60-iteration run of a 3x3 map of the preset's kind (its rules, codes of 4x4,
  the ordered start and 300 refinement pairs), so that the phases below hold no loading;
- ``ordered_start``: the model and its iteration-0 weights (the cross-view start);
- ``training``: the preset's iterations (``partial_fit``);
- ``refinement``: the preset's rounds (``refine``);
- ``write``: the model file (``save``);
- ``evaluation_fold_check``: the command's last step, the fold warning's evaluation of 4,000
  test pairs.

Ratios are taken within one process: ``refinement / training`` and ``whole / training``
(whole: the sum of the phases, the process's CPU seconds). Medians over ``--repeats``.
With ``--cli`` the real command also runs (``--repeats`` times, alternating with the phase
runs) and its CPU seconds (the child's, ``resource``) are reported beside the phases' sum.
``--bandwidth``: a STREAM-like triad (``bench_bandwidth.py``'s, one thread) measured in the
same run and written beside the ratios, with the training's memory-bandwidth bound (the
bytes per iteration that ``bench_bandwidth.py`` counted, ``benchmarks/results/bandwidth.json``,
over this run's triad) and the training's share of it (bound seconds / training CPU seconds).
Writes ``benchmarks/results/train-phases.json``.
"""

from __future__ import annotations

import argparse
import json
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import _common

ROOT = Path(__file__).resolve().parent
PHASES = ("startup", "numba_load", "ordered_start", "training", "refinement", "write",
          "evaluation_fold_check")  # fmt: skip


def _self_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def child(preset: str, seed: int) -> dict[str, Any]:
    """One run of the command's steps, timed (module docstring)."""
    from sigmapi.cli._common import DEFAULT_PRESET  # noqa: F401  (the command's imports)
    from sigmapi.cli.train import _warn_if_folded
    from sigmapi.config import load_preset
    from sigmapi.model.som import SigmaPiSOM

    cfg = load_preset(preset).replace(seed=seed)
    out: dict[str, Any] = {"startup": _self_cpu()}
    c = time.process_time()
    tiny = cfg.replace(map_shape=(3, 3), x_shape=(4, 4), y_shape=(4, 4), iterations=60,
                       refine_pairs=300)  # fmt: skip
    SigmaPiSOM(tiny).fit()
    out["numba_load"] = time.process_time() - c
    with tempfile.TemporaryDirectory() as tmp:
        steps = (
            ("ordered_start", lambda m: m.partial_fit(iterations=0)),
            ("training", lambda m: m.partial_fit(iterations=cfg.iterations)),
            ("refinement", lambda m: m.refine()),
            ("write", lambda m: m.save(Path(tmp) / "m.npz")),
            ("evaluation_fold_check", _warn_if_folded),
        )
        model = SigmaPiSOM(cfg)
        for name, step in steps:
            c = time.process_time()
            step(model)
            out[name] = time.process_time() - c
    out["whole"] = _self_cpu()
    out["refined"] = model.refined_
    out["iterations"] = model.t_
    return out


def cli_run(preset: str, seed: int) -> float:
    """CPU seconds of the real ``sigmapi train`` (a child process)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [sys.executable, "-m", "sigmapi.cli", "train", "--preset", preset, "--seed",
               str(seed), "--out", str(Path(tmp) / "m.npz"), "--quiet"]  # fmt: skip
        subprocess.run(cmd, check=True, capture_output=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def triad_gb_s() -> float:
    """The one-thread triad of ``bench_bandwidth.py`` (GB/s), in a fresh process."""
    script = ROOT / "bench_bandwidth.py"
    return float(_common.run_child(script, ["triad", "256"])["one_thread_gb_s"])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--child", nargs=2, metavar=("PRESET", "SEED"), help=argparse.SUPPRESS)
    parser.add_argument("--preset", default="paper-2d")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--cli", action="store_true", help="also time the real command")
    parser.add_argument("--bandwidth", action="store_true", help="measure the triad too")
    parser.add_argument("--out", default=str(ROOT / "results" / "train-phases.json"))
    args = parser.parse_args()
    if args.child:
        print(json.dumps(child(args.child[0], int(args.child[1]))))
        return
    runs: list[dict[str, Any]] = []
    cli: list[float] = []
    for _ in range(args.repeats):
        runs.append(_common.run_child(__file__, [args.preset, str(args.seed)]))
        if args.cli:
            cli.append(cli_run(args.preset, args.seed))
    med = {k: statistics.median(r[k] for r in runs) for k in (*PHASES, "whole")}
    ratios = {
        "refinement_over_training": statistics.median(
            r["refinement"] / r["training"] for r in runs
        ),
        "whole_over_training": statistics.median(r["whole"] / r["training"] for r in runs),
    }
    result: dict[str, Any] = {
        "command": "python benchmarks/bench_train_phases.py " + " ".join(sys.argv[1:]),
        "preset": args.preset,
        "seed": args.seed,
        "cpu_s_median": {k: round(v, 3) for k, v in med.items()},
        "ratios_median": {k: round(v, 3) for k, v in ratios.items()},
        "runs": [
            {k: round(v, 3) if isinstance(v, float) else v for k, v in r.items()} for r in runs
        ],
    }
    if cli:
        result["cli_cpu_s"] = [round(c, 2) for c in cli]
        result["cli_over_training_median"] = round(
            statistics.median(c / r["training"] for c, r in zip(cli, runs, strict=True)), 3
        )
    if args.bandwidth:
        gb_s = triad_gb_s()
        counted = json.loads((ROOT / "results" / "bandwidth.json").read_text("utf-8"))
        per_it = counted["presets"][args.preset]["variants"]["fast"]["bytes_per_iteration"]
        bound = per_it * runs[0]["iterations"] / (gb_s * 1e9)
        result["bandwidth"] = {
            "triad_one_thread_gb_s": round(gb_s, 2),
            "bytes_per_iteration_counted": per_it,
            "training_bound_s": round(bound, 2),
            "training_share_of_bound_median": round(
                statistics.median(bound / r["training"] for r in runs), 3
            ),
        }
    result["machine"] = _common.machine()
    _common.write_result(Path(args.out), result)
    print(json.dumps({k: result[k] for k in ("cpu_s_median", "ratios_median")}, indent=1))


if __name__ == "__main__":
    main()
