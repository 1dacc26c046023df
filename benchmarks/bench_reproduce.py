"""The default ``sigmapi reproduce``, run as a user runs it, timed: ``results/reproduce.json``.

Usage (from the repository root)::

    python benchmarks/bench_reproduce.py                 # the default run (seeds 0-9)
    python benchmarks/bench_reproduce.py --args --quick  # anything after --args goes to it

Runs ``sigmapi reproduce --out DIR --force --models none`` (plus ``--args``) in a child
process and writes ``benchmarks/results/reproduce.json``: the command, the wall seconds, the
CPU seconds of the run and its worker processes (user + system, from ``getrusage`` of the
children), their peak resident memory, the 1-minute load average sampled every 10 s while it
ran (the machine is shared: wall seconds depend on it; CPU seconds much less), and under
``metrics`` the run's whole ``metrics.json`` (its keys: the docstring of
``sigmapi.experiments.reproduce.run``). The docs render the reproduction page from this file.
Run it with ``NUMBA_CACHE_DIR`` set to an empty folder to count numba's compile as a fresh
install does (``numba_cache`` says which). A run with other options (``--args``, e.g. fewer
seeds on a loaded machine) adds ``default_run_estimate``: the default run's CPU and 2-core
wall seconds extrapolated from it (:func:`default_estimate`).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

from _common import commit, machine, write_result

ROOT = Path(__file__).resolve().parent
SRC = ROOT.parent / "src"


def _sample_load(stop: threading.Event, into: list[float]) -> None:
    while not stop.wait(10.0):
        into.append(os.getloadavg()[0])


def _compile_cpu(run: dict[str, Any]) -> float:
    """CPU seconds of a job's one-time compile (0 if it compiled nothing)."""
    return float(run.get("compile_cpu_seconds", 0.0))


def _job_cpu(run: dict[str, Any]) -> float:
    """CPU seconds of a job without its compile (``cpu_seconds`` excludes it)."""
    return float(run["cpu_seconds"])


def default_estimate(metrics: dict[str, Any], cpu: float) -> dict[str, Any]:
    """CPU and 2-core wall seconds of the default run, from a run on fewer seeds.

    Per preset, the median CPU seconds of one seed's job without its compile, times the
    seeds the default run trains there; plus this run's compile seconds and the CPU seconds
    spent outside the training jobs (the ceilings, figures, the reach section: none depends
    on the number of seeds). The wall estimate spreads the training jobs over 2 cores and
    counts the rest as serial (an upper bound for it: the reach section runs in parallel).
    """
    from sigmapi.experiments.reproduce.results import ReproduceConfig
    from sigmapi.experiments.reproduce.run import REPRODUCE

    seeds, seeds_2d = len(REPRODUCE.seeds), ReproduceConfig().seeds_2d
    jobs, jobs_default, compiled = 0.0, 0.0, 0.0
    per_preset = {}
    for name, p in metrics["presets"].items():
        runs = p["runs"]
        per_seed = sorted(_job_cpu(r) for r in runs)
        median = per_seed[len(per_seed) // 2]
        n = seeds if len(p["config"]["map_shape"]) == 1 else min(seeds, seeds_2d or seeds)
        jobs += sum(r["cpu_seconds"] for r in runs)
        compiled += sum(_compile_cpu(r) for r in runs)
        jobs_default += n * median
        per_preset[name] = {"seeds_run": len(runs), "seeds_default": n,
                            "cpu_per_seed_median": round(median, 1)}  # fmt: skip
    rest = cpu - jobs
    return {
        "how": " ".join((default_estimate.__doc__ or "").split()),
        "presets": per_preset,
        "cpu_outside_training_jobs": round(rest, 1),
        "compile_seconds": round(compiled, 1),
        "cpu_seconds": round(jobs_default + compiled + rest, 1),
        "wall_seconds_2_cores": round((jobs_default + compiled) / 2 + rest, 1),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=str(ROOT / "results" / "reproduce.json"))
    parser.add_argument("--report", default=None, help="report folder (default: a temp dir)")
    parser.add_argument("--args", nargs=argparse.REMAINDER, default=[],
                        help="more options of sigmapi reproduce")  # fmt: skip
    args = parser.parse_args()
    report = Path(args.report or tempfile.mkdtemp(prefix="reproduce-"))
    options = ["--out", str(report), "--force", "--models", "none", *args.args]
    default = not args.args
    code = "import sys; from sigmapi.cli import main; sys.exit(main(sys.argv[1:]))"
    cmd = [sys.executable, "-c", code, "reproduce", *options]
    cache = os.environ.get("NUMBA_CACHE_DIR")
    cold = cache is not None and (not Path(cache).exists() or not any(Path(cache).iterdir()))
    loads = [os.getloadavg()[0]]
    stop = threading.Event()
    sampler = threading.Thread(target=_sample_load, args=(stop, loads), daemon=True)
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    sampler.start()
    proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
    wall = time.perf_counter() - t0
    stop.set()
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed ({proc.returncode}):\n{proc.stderr[-3000:]}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    metrics = json.loads((report / "metrics.json").read_text(encoding="utf-8"))
    load = {"samples": loads, "median": sorted(loads)[len(loads) // 2], "max": max(loads)}
    result: dict[str, Any] = {
        "command": "sigmapi reproduce " + " ".join(["--out", "DIR", *options[2:]]),
        "made_by": "python benchmarks/bench_reproduce.py " + " ".join(sys.argv[1:]),
        "commit": commit(SRC),
        "machine": machine(note="shared by other jobs: see load_average_1min"),
        "wall_seconds": round(wall, 1),
        "cpu_seconds": round(cpu, 1),
        "cpu_per_wall": round(cpu / wall, 2),
        "peak_rss_mb": round(after.ru_maxrss / 1024, 1),  # the largest child process
        "load_average_1min": load,
        "numba_cache": (
            f"cold: NUMBA_CACHE_DIR={cache} empty at the start, numba's compile counted, as "
            "on a fresh install"
            if cold
            else f"as found ({cache or 'beside the sources'})"
        ),
        "default_run_estimate": None if default else default_estimate(metrics, cpu),
        "console": proc.stdout.strip().splitlines(),
        "metrics": metrics,
    }
    write_result(Path(args.out), result)


if __name__ == "__main__":
    main()
