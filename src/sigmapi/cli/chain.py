"""``sigmapi chain``: a chain of two maps (retina + eye -> head -> body) against one map.

Prints a table per seed and the summary (or, with ``--json``, one JSON object: ``settings``,
``seeds`` and ``summary`` of :func:`sigmapi.experiments.chain.run_chain`).
"""

from __future__ import annotations

import argparse
import json
from typing import Any

from sigmapi.cli._common import apply_set_flags
from sigmapi.config import load_preset
from sigmapi.experiments.chain import CODES, run_chain

__all__ = ["cmd_chain", "register"]


def register(sub: Any) -> None:
    """Add the ``chain`` sub-command."""
    p = sub.add_parser(
        "chain",
        help="a chain of two maps (retina -> head -> body) against one map on the whole task",
        description="Train map A (retina + eye -> head-centred) on its task, map B (A's "
        "response + head -> body-centred) and one third-order map on the whole transformation "
        "on the same triples, and score both routes by the same metrics.",
    )
    p.add_argument("--preset", default="paper-1d",
                   help="1-D preset of all maps (default paper-1d), crossview")  # fmt: skip
    p.add_argument("--set", action="append", metavar="KEY=VALUE",
                   help="override a key of the preset, e.g. --set iterations=50000")  # fmt: skip
    p.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2],
                   help="seeds (default 0 1 2)")  # fmt: skip
    p.add_argument("--train-pairs", type=int, default=20_000,
                   help="view pairs to train B and the single map (default 20000)")  # fmt: skip
    p.add_argument("--n-test", type=int, default=10_000,
                   help="calibration and test triples (default 10000)")  # fmt: skip
    p.add_argument("--code", choices=CODES, default="response",
                   help="what map A hands to map B (default: its response)")  # fmt: skip
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.set_defaults(func=cmd_chain)


def cmd_chain(args: argparse.Namespace) -> int:
    cfg = load_preset(args.preset).replace(ordering="crossview")
    cfg = apply_set_flags(cfg, args.set)
    result = run_chain(args.seeds, config=cfg, train_pairs=args.train_pairs,
                       n_test=args.n_test, code=args.code)  # fmt: skip
    if args.json:
        print(json.dumps(result))
        return 0
    print("seed  route   z error  same winner  order R^2  usage  weights  seconds")
    for r in result["seeds"]:
        for route in ("chain", "single"):
            m = r[route]
            print(f"{r['seed']:<5d} {route:7s} {m['z_error']:7.3f}  {m['view_consistency']:11.3f}"
                  f"  {m['order_r2']:9.3f}  {m['usage']:5.2f}  {m['weights']:7d}"
                  f"  {m['train_seconds']:7.1f}")  # fmt: skip
    s = result["summary"]
    print(f"{s['met']} of {s['n_seeds']} seeds: chain z error <= {s['target_ratio']:g} x the "
          f"single map's (median ratio {s['ratio_median']:.2f}, worst "
          f"{s['ratio_worst']:.2f})")  # fmt: skip
    return 0
