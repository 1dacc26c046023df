"""Has every reach learner levelled off within the episode budget? The default comparison run
longer, and each learner's success and rise read at the default budget and at the end.

Usage (from the repository root)::

    python benchmarks/bench_reach_levelling.py                    # sigmapi reach, 1200 episodes
    python benchmarks/bench_reach_levelling.py --from DIR         # a run already made there

The run is ``sigmapi reach --episodes N --seeds S... --out DIR --json --quiet``, as a user runs
it (the experiment's defaults otherwise: the 2-D task, the 15x15 paper-2d map, 600 episodes
by default). Its first 600 episodes are those of the default run of the same seeds (the
episodes' starts are drawn in order, the learners' seeds do not depend on the budget), so one
long run answers both questions: did the learners level off by episode 600, and by the end?

Writes ``benchmarks/results/reach-levelling.json``: per checkpoint (the default budget and
the end) and state, the success rate over the ``final_episodes`` before it and the rise
across them (a least-squares line through the seeds' mean curve, blocks of ``block``
episodes; the experiment's own ``final_rise`` fits each seed's episodes, which the result
file of a run does not keep), whether the learner levelled off (rise below
``plateau_rise``), how often that criterion flags a simulated learner that has levelled
off (or rises by a given amount) with as many seeds and episodes, and the run's wall-clock
and CPU seconds (the command and its worker processes; ``--from``: those of the
``--time-log`` of GNU ``time -v``, when given).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import commit, machine, write_result
from sigmapi.experiments.reach.config import ReachRunConfig

ROOT = Path(__file__).resolve().parent
RESULTS = ROOT / "results"
SRC = ROOT.parent / "src"


def window_rise(episode: list[float], success: list[float], end: int, window: int) -> dict:
    """Success over the ``window`` episodes up to ``end`` (the blocks ending in it) and its
    rise across them: the slope of a least-squares line through the block means, times
    ``window - 1``."""
    ep, rate = np.asarray(episode), np.asarray(success, dtype=np.float64)
    inside = (ep > end - window) & (ep <= end)
    if inside.sum() < 2:
        raise ValueError(f"fewer than 2 blocks end in episodes {end - window + 1}-{end}")
    x, y = ep[inside], rate[inside]
    slope = float(np.polyfit(x, y, 1)[0])
    return {"success": float(y.mean()), "rise": slope * (window - 1), "blocks": int(inside.sum())}


def summarise(result: dict[str, Any], checkpoint: int) -> dict[str, Any]:
    """Per checkpoint and state: success, rise, levelled off (see the module docstring)."""
    run = result["config"]["run"]
    episodes, window, limit = run["episodes"], run["final_episodes"], _plateau_rise(run)
    out: dict[str, Any] = {}
    for end in sorted({checkpoint, episodes}):
        rows = {}
        for state, c in result["curves"].items():
            row = window_rise(c["episode"], c["success"], end, window)
            rows[state] = {**row, "levelled_off": row["rise"] < limit}
        out[str(end)] = rows
    return out


def flag_rates(n_seeds: int, window: int, limit: float, trials: int = 4000) -> list[dict]:
    """How often the criterion (mean rise over seeds >= ``limit``) flags a learner, by
    simulation: ``n_seeds`` seeds of ``window`` Bernoulli episodes whose success probability
    rises linearly by ``true_rise`` around ``p`` (0: a learner that has levelled off), the
    rise fitted per seed as the experiment fits it (``ReachResult.final_rise_per_seed``)."""
    rng = np.random.default_rng(0)
    t = np.arange(window) - (window - 1) / 2.0
    rows = []
    for p, true_rise in ((0.5, 0.0), (0.9, 0.0), (0.5, 0.05), (0.5, 0.1), (0.5, 0.2)):
        prob = p + true_rise * t / (window - 1)
        y = (rng.random((trials, n_seeds, window)) < prob).astype(np.float64)
        rise = ((y @ t) / float(t @ t) * (window - 1)).mean(axis=1)
        rows.append({"p": p, "true_rise": true_rise, "flagged": float((rise >= limit).mean()),
                     "rise_sd": float(rise.std())})  # fmt: skip
    return rows


def _plateau_rise(run: dict[str, Any]) -> float:
    """The run's threshold; a result written before the config had one: today's default."""
    return float(run.get("plateau_rise", ReachRunConfig().plateau_rise))


def _time_log(path: Path) -> dict[str, float]:
    """Wall and CPU seconds from the output of GNU ``time -v``."""
    text = path.read_text("utf-8")

    def grab(label: str) -> float:
        m = re.search(rf"{re.escape(label)}: ([0-9.:]+)", text)
        if m is None:
            raise ValueError(f"{path}: no {label!r} line")
        parts = [float(p) for p in m.group(1).split(":")]
        return sum(p * 60**i for i, p in enumerate(reversed(parts)))

    return {
        "wall_s": grab("Elapsed (wall clock) time (h:mm:ss or m:ss)"),
        "cpu_s": grab("User time (seconds)") + grab("System time (seconds)"),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--episodes", type=int, default=1200)
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3, 4])
    ap.add_argument("--checkpoint", type=int, default=600, help="the default budget")
    ap.add_argument("--from", dest="src_dir", type=Path, help="read DIR/result.json, run nothing")
    ap.add_argument("--time-log", type=Path, help="with --from: the run's `time -v` output")
    args = ap.parse_args()
    if args.src_dir is not None:
        result = json.loads((args.src_dir / "result.json").read_text("utf-8"))
        timing = _time_log(args.time_log) if args.time_log else None
        command = None
    else:
        out = Path(tempfile.mkdtemp(prefix="reach-levelling."))
        seeds = [str(s) for s in args.seeds]
        command = ["sigmapi", "reach", "--episodes", str(args.episodes), "--seeds", *seeds,
                   "--out", str(out), "--force", "--json", "--quiet"]  # fmt: skip
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        proc = subprocess.run(
            [sys.executable, "-m", "sigmapi.cli", *command[1:]],
            capture_output=True, text=True, check=False,
            env=dict(os.environ, PYTHONPATH=str(SRC)),
        )  # fmt: skip
        wall = time.perf_counter() - t0
        if proc.returncode != 0:
            raise SystemExit(f"{' '.join(command)} failed:\n{proc.stderr[-3000:]}")
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
        timing = {"wall_s": wall, "cpu_s": cpu}
        result = json.loads(proc.stdout)
    run = result["config"]["run"]
    write_result(
        RESULTS / "reach-levelling.json",
        {
            "what": "sigmapi reach run past its default budget: success and rise per learner "
            "at the default budget and at the end (module docstring of the script)",
            "command": " ".join(command) if command else None,
            "seeds": result["config"]["seeds"],
            "seeds_note": "the experiment's default seeds; nothing was tuned on them (the "
            "threshold plateau_rise is the config's default, set before the run)",
            "episodes": run["episodes"],
            "final_episodes": run["final_episodes"],
            "block": run["block"],
            "plateau_rise": _plateau_rise(run),
            "checkpoints": summarise(result, args.checkpoint),
            "criterion_noise": {
                "what": "share of simulated learners flagged 'still rising' (4000 trials each, "
                "numpy seed 0), as many seeds and episodes as the run",
                "rows": flag_rates(
                    len(result["config"]["seeds"]), run["final_episodes"], _plateau_rise(run)
                ),
            },
            "curves": {
                s: {"episode": c["episode"], "success": c["success"]}
                for s, c in result["curves"].items()
            },
            "timing": timing,
            "commit": commit(SRC),
            "machine": machine(),
        },
    )


if __name__ == "__main__":
    main()
