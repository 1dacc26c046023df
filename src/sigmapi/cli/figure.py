"""``sigmapi figure NAME MODEL --out FILE``: one of the figures of the report for a model file."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

import numpy as np

from sigmapi import _validate
from sigmapi.analysis.curves import LearningCurve, checkpoints
from sigmapi.cli._common import check_output, declare_path
from sigmapi.errors import UsageError
from sigmapi.experiments.reproduce.results import CURVE_TEST, N_CHECKPOINTS
from sigmapi.model.som import load_model
from sigmapi.progress import progress_callback
from sigmapi.viz.figures import DPI, FIGURES, draw_figure

__all__ = ["add_arguments", "cmd_figure"]


MAX_LABEL = 200
"""Longest ``--label`` (a title's name for the model)."""

MAX_REPLAY = 100_000_000
"""Most iterations ``figure curves`` replays (the experiments' bound on a map's iterations)."""


def _label(text: str | None) -> str | None:
    """``--label`` checked: one line of at most :data:`MAX_LABEL` characters (titles draw it
    as plain text: a ``$`` is no mathtext)."""
    if text is None:
        return None
    shown = repr(text[:40]) + ("..." if len(text) > 40 else "")
    if len(text) > MAX_LABEL:
        raise UsageError(
            f"--label must be at most {MAX_LABEL} characters, got {len(text):,} ({shown}); "
            "give a short name for the model"
        )
    if any(ord(c) < 32 or ord(c) == 127 for c in text):
        raise UsageError(
            f"--label must be one line without control characters, got {shown}; "
            "give a short name for the model"
        )
    return text


def cmd_figure(args: argparse.Namespace) -> int:
    label = _label(args.label)
    out = check_output(args.out, args.force, "--out")
    fmt = out.suffix.lower().lstrip(".")
    allowed = ("png", "pdf", "svg")
    if fmt not in allowed:
        raise UsageError(f"--out must end in one of {['.' + a for a in allowed]}, got {str(out)!r}")
    if args.seed is not None:
        _validate.integer("--seed", args.seed, 0, fix="seeds are ints >= 0", error=UsageError)
    dpi = _validate.integer("--dpi", args.dpi, 20, 1200, fix="300 for print", error=UsageError)
    model = load_model(args.model)
    if not model.is_fitted or model.t_ == 0:
        raise UsageError(f"model {args.model!r} has not been trained (0 iterations)")
    if len(model.x_shape) > 2 or len(model.map_shape) > 2:
        raise UsageError("figures exist for 1-D and 2-D maps and inputs only")
    if args.name == "net" and len(model.map_shape) != len(model.x_shape):
        raise UsageError(
            f"the net figure needs a map with as many dimensions as z; this map is "
            f"{len(model.map_shape)}-D and z is {len(model.x_shape)}-D"
        )
    curves = None
    if args.name == "curves" and model.t_ > MAX_REPLAY:
        raise UsageError(
            f"model {args.model!r} claims {model.t_:,} iterations; `sigmapi figure curves` "
            f"replays the run, at most {MAX_REPLAY:,} iterations: draw another figure of "
            "this model, or train one with fewer iterations"
        )
    if args.name == "curves":
        # the training data are a pure function of the seed: re-running the model's schedule
        # from its seed replays the same run, now with checkpoints
        twin = model.replay_twin()
        callback, bar = progress_callback(model.t_, "replaying the run", disable=args.quiet or None)
        at = checkpoints(model.t_, N_CHECKPOINTS)
        curve = LearningCurve(at=at, n_test=CURVE_TEST, then=callback)
        with bar:
            twin.fit(iterations=model.t_, callback=curve)
        if not np.allclose(twin.weights_, model.weights_, rtol=1e-6, atol=1e-9):
            print(
                "note: the replayed run ended with weights that differ from the file's "
                "(another backend?); curves show the replay",
                file=sys.stderr,
            )
        curves = [curve.to_dict()]
    label = label if label is not None else Path(args.model).name
    draw_figure(args.name, model, out, curves=curves, label=label, seed=args.seed, dpi=dpi)
    print(f"wrote {out}", file=sys.stderr)
    return 0


def add_arguments(p: Any) -> None:
    """The options of ``sigmapi figure`` (its parser is filled when the command is used)."""
    p.add_argument("name", choices=FIGURES, help="which figure")
    p.add_argument("model", help="model file written by `sigmapi train` or `sigmapi reproduce`")
    p.add_argument("--out", required=True, help="image file to write (.png, .pdf or .svg)")
    p.add_argument("--seed", type=int, default=0, help="seed of the figure's sampled inputs")
    p.add_argument(
        "--label",
        help=f"how titles name the model, plain text of at most {MAX_LABEL} characters "
        "(default: the file name)",
    )
    p.add_argument(
        "--dpi",
        type=int,
        default=DPI,
        help=f"resolution of .png figures (default {DPI}; 300 for print; .pdf and "
        ".svg are vector graphics)",
    )
    p.add_argument("--force", action="store_true", help="overwrite --out if it exists")
    p.add_argument("--quiet", action="store_true", help="no progress bar (curves replay the run)")
    declare_path(p, "model", "model", "input")
    declare_path(p, "out", "--out", "output")
    p.set_defaults(func=cmd_figure)
