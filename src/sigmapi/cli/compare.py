"""``sigmapi compare``: the Sigma-Pi map beside first-order SOMs, MiniSom, a basis-function
network and an RBM, all trained on the same two-view data (:mod:`sigmapi.baselines`).

Prints a table (or, with ``--json``, one JSON object whose ``"methods"`` list holds one object
per method: ``name``, ``view_consistency``, ``z_error``, ``labels_used``, ...) and writes the
figure to ``--out`` with its caption beside it (``.txt``).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
from typing import Any

from sigmapi.cli._common import check_output
from sigmapi.errors import UsageError
from sigmapi.experiments.compare import (
    METHODS,
    QUICK,
    QUICK_SEEDS,
    SEEDS,
    CompareConfig,
    check_installed,
    run_compare,
)
from sigmapi.progress import Progress

__all__ = ["cmd_compare", "register"]


def register(sub: Any) -> None:
    """Add the ``compare`` sub-command."""
    p = sub.add_parser(
        "compare",
        help="the Sigma-Pi map beside the baselines a user would pick instead",
        description="Train the Sigma-Pi map, its ablations, first-order SOMs (sigmapi's and "
        "MiniSom), a basis-function network and an RBM + read-out on the same two-view data "
        "and score them by the same metrics.",
    )
    p.add_argument("--quick", action="store_true",
                   help="a first look in about a minute (2 seeds, less data)")  # fmt: skip
    p.add_argument("--preset", help="the task and Sigma-Pi settings (default paper-1d)")
    p.add_argument("--set", action="append", metavar="KEY=VALUE",
                   help="override a key of the preset, e.g. --set iterations=50000")  # fmt: skip
    p.add_argument("--seeds", type=int, nargs="+", help="seeds (default 0 1 2 3 4; quick 0 1)")
    for name, what in (("train-pairs", "view pairs per seed"),
                       ("som-iterations", "updates of the first-order maps"),
                       ("rbm-epochs", "RBM training passes"),
                       ("n-test", "test and calibration z's")):  # fmt: skip
        p.add_argument(f"--{name}", type=int, help=f"{what} (default: see --help of the API)")
    p.add_argument("--methods", help=f"comma-separated subset of: {', '.join(METHODS)}")
    p.add_argument("--out", default="compare.png", help="figure file (default compare.png)")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.add_argument("--force", action="store_true", help="overwrite existing output files")
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    p.set_defaults(func=cmd_compare)


def _config(args: argparse.Namespace) -> CompareConfig:
    base = QUICK if args.quick else CompareConfig()
    changes: dict[str, Any] = {}
    for key in ("preset", "train_pairs", "som_iterations", "rbm_epochs", "n_test"):
        if getattr(args, key) is not None:
            changes[key] = getattr(args, key)
    if args.set:
        changes["overrides"] = tuple(args.set)
    if args.methods is not None:
        changes["methods"] = tuple(m.strip() for m in args.methods.split(",") if m.strip())
    return dataclasses.replace(base, **changes)


def cmd_compare(args: argparse.Namespace) -> int:
    from sigmapi.baselines.plots import compare_figure  # matplotlib: only when drawing

    out = check_output(args.out, args.force, "figure file")
    if out.suffix.lower() not in (".png", ".pdf", ".svg"):
        raise UsageError(f"--out must end in .png, .pdf or .svg, got {str(out)!r}")
    cfg = _config(args)
    check_installed(cfg.methods)
    seeds = args.seeds if args.seeds is not None else (QUICK_SEEDS if args.quick else SEEDS)
    result = run_compare(cfg, None if args.quiet else Progress(), seeds=seeds)
    fig = compare_figure(result.to_dict())
    fig.savefig(out, dpi=120)
    caption = result.caption()
    out.with_suffix(".txt").write_text(caption + "\n", encoding="utf-8")
    if args.json:
        print(json.dumps(result.to_dict()))
    else:
        print(result.table())
        print(caption)
    print(f"wrote {out} ({result.seconds:.0f} s)", file=sys.stderr)
    return 0
