"""``sigmapi sweep SPEC.toml --out DIR``: parameters x seeds (:mod:`sigmapi.experiments.sweep`)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from sigmapi.cli._common import add_workers_flag
from sigmapi.errors import UsageError
from sigmapi.executor import ENGINES
from sigmapi.experiments.sweep import FIGURE, RESULTS, SweepSpec, draw_summary, run_sweep
from sigmapi.progress import jobs_done

__all__ = ["cmd_sweep", "register"]


def cmd_sweep(args: argparse.Namespace) -> int:
    spec = SweepSpec.read(args.spec)
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise UsageError(f"--out {str(out)!r} is a file; give a folder for the sweep")
    if args.memory_budget is not None and args.memory_budget <= 0:
        raise UsageError(f"--memory-budget must be a positive number of GiB, got "
                         f"{args.memory_budget}")  # fmt: skip
    if args.address is not None and args.engine != "dask":
        raise UsageError("--address names a Dask scheduler; pass it with --engine dask")
    budget = None if args.memory_budget is None else int(args.memory_budget * 2**30)
    state: dict[str, Any] = {}

    def on_plan(n_run: int, n_skip: int, reason: str) -> None:
        print(f"sweep: {n_run + n_skip} runs, {n_skip} finished already, {n_run} to run; "
              f"engine {args.engine}, {reason}", file=sys.stderr)  # fmt: skip
        done, bar = jobs_done(n_run, "sweep", disable=args.quiet)
        state["done"], state["bar"] = done, bar

    def on_done(ok: bool, line: str) -> None:
        state["done"](ok, line)

    try:
        rows = run_sweep(spec, out, engine=args.engine, workers=args.workers,
                         memory_budget=budget, address=args.address,
                         retry_failed=args.retry_failed, on_plan=on_plan,
                         on_done=on_done)  # fmt: skip
    finally:
        if "bar" in state:
            state["bar"].close()
    figure = draw_summary(spec, rows, out / FIGURE, args.metric)
    failed = sum(str(r.get("status")) != "ok" for r in rows)
    print(f"wrote {out / RESULTS} ({len(rows)} runs, {failed} failed) and {figure}",
          file=sys.stderr)  # fmt: skip
    return 0


def register(sub: Any) -> None:
    """Add ``sigmapi sweep`` to the sub-parsers ``sub``."""
    p = sub.add_parser("sweep", help="train and evaluate a grid of parameters x seeds")
    p.add_argument("spec", help="sweep spec (TOML: preset, seeds, [set], [grid]; see README)")
    p.add_argument("--out", required=True, help="folder for results.csv and sweep.png; a "
                   "folder with results of the same spec resumes it")  # fmt: skip
    p.add_argument("--engine", choices=ENGINES, default="local",
                   help="local: a process pool on this machine (default); dask: a Dask "
                   "cluster (--address, or a local one)")  # fmt: skip
    add_workers_flag(p, "runs")
    p.add_argument("--memory-budget", type=float, default=None, metavar="GIB",
                   help="memory the parallel runs may use together (default: half of the "
                   "available memory)")  # fmt: skip
    p.add_argument("--address", help="Dask scheduler address, e.g. tcp://10.0.0.5:8786")
    p.add_argument("--retry-failed", action="store_true",
                   help="run failed runs again (default: finished runs, failed or not, are "
                   "kept)")  # fmt: skip
    p.add_argument("--metric", default="order_r2", help="metric of the summary figure "
                   "(default: order_r2)")  # fmt: skip
    p.add_argument("--quiet", action="store_true", help="no progress bar or lines")
    p.set_defaults(func=cmd_sweep)
