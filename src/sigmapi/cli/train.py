"""``sigmapi train``, ``sigmapi evaluate`` and ``sigmapi presets``."""

from __future__ import annotations

import argparse
import json
import sys
import textwrap
from pathlib import Path

import numpy as np

from sigmapi import _validate
from sigmapi._lock import output_lock
from sigmapi.checkpoints import (
    checkpoint_dir,
    find_resumable,
    remove_checkpoints,
    write_checkpoint,
)
from sigmapi.cli._common import (
    DEFAULT_PRESET,
    LazyParser,
    add_config_flags,
    check_output,
    config_keys_help,
    declare_path,
    resolve_config,
)
from sigmapi.config import SOMConfig, list_presets, load_preset
from sigmapi.errors import ModelFileError, UsageError
from sigmapi.metrics import (
    FOLD_THRESHOLD,
    chebyshev,
    evaluate,
    evaluation_sets,
    fold_indicators,
    hard_scores,
)
from sigmapi.model.som import SigmaPiSOM, load_model
from sigmapi.progress import counter, progress_callback

__all__ = ["cmd_evaluate", "cmd_presets", "cmd_train", "register"]


def cmd_train(args: argparse.Namespace) -> int:
    cfg = resolve_config(args)
    every = args.checkpoint_every
    if every is not None:
        _validate.integer("--checkpoint-every", every, 1, fix="in iterations", error=UsageError)
    # --resume continues the same run, so it may replace that run's --out (checked below)
    out = check_output(args.out, args.force or args.resume)
    with output_lock(out, f"--out {str(out)!r}"):  # one train per model file at a time
        check_output(out, args.force or args.resume)  # again: one may have finished meanwhile
        return _train(args, cfg, out, every)


def _train(args: argparse.Namespace, cfg: SOMConfig, out: Path, every: int | None) -> int:
    folder = checkpoint_dir(out)
    model = None
    if args.resume:
        found = find_resumable(folder, cfg)
        for note in found.skipped:
            if "another config" in note:
                raise UsageError(
                    f"checkpoint {note}; resume with the command line that started the run, "
                    f"or remove {str(folder)!r}"
                )
            print(f"sigmapi train: skipped damaged checkpoint {note}", file=sys.stderr)
        model = found.model
        if model is not None:
            print(f"resuming from {found.path} (iteration {model.t_})", file=sys.stderr)
        elif out.exists() and not args.force:
            model = _finished_run(out, cfg)
            if model.t_ >= cfg.iterations and model.refined_ >= model.refine_total:
                print(
                    f"{out} is this run, complete ({model.t_} iterations); nothing to do",
                    file=sys.stderr,
                )
                return 0
            print(f"resuming from {out} (iteration {model.t_})", file=sys.stderr)
    if model is None:
        model = SigmaPiSOM(cfg)
        model.partial_fit(iterations=0)  # initial weights, iteration 0
    callback, bar = progress_callback(
        cfg.iterations, f"train {args.preset}", start=model.t_, disable=args.quiet or None
    )
    with bar:
        while model.t_ < cfg.iterations:
            step = cfg.iterations - model.t_
            if every is not None:
                step = min(step, every - model.t_ % every)
            model.partial_fit(iterations=step, callback=callback)
            if every is not None and model.t_ % every == 0 and model.t_ < cfg.iterations:
                write_checkpoint(model, folder)
    if model.refined_ < model.refine_total:  # the config's refinement (rules/refinement.py)
        left = model.refine_total - model.refined_
        tick, bar = counter(left, f"refine {args.preset}", "pair", disable=args.quiet or None)
        seen = model.refined_

        def refined(m: SigmaPiSOM) -> None:
            nonlocal seen
            tick(m.refined_ - seen, "")
            seen = m.refined_

        with bar:
            model.refine(callback=refined)
    model.save(out, compress=args.compress)
    print(f"wrote {out} ({model.t_} iterations, backend {model.backend})", file=sys.stderr)
    if not args.keep_checkpoints:
        remove_checkpoints(folder)
    _warn_if_folded(model)
    return 0


def _finished_run(out: Path, cfg: SOMConfig) -> SigmaPiSOM:
    """The model in ``out`` if it is a run of ``cfg`` (``--resume`` may continue it), else a
    UsageError: resuming must never replace the file of another run."""
    try:
        model = load_model(out)
    except ModelFileError as exc:
        raise UsageError(
            f"--resume found no checkpoint in {str(checkpoint_dir(out))!r}, and --out "
            f"{str(out)!r} is not a model of this run ({exc}); pass --force to replace it"
        ) from None
    if model.config != cfg or model.t_ > cfg.iterations:
        raise UsageError(
            f"--resume found no checkpoint in {str(checkpoint_dir(out))!r}, and --out "
            f"{str(out)!r} holds a model made with another config; pass --force to replace "
            "it, or choose another --out"
        )
    return model


def _warn_if_folded(model: SigmaPiSOM, n: int = 4000) -> None:
    """One warning line when the trained map looks folded (the z-free fold score)."""
    _, test = evaluation_sets(model, n)
    scores = hard_scores(model, test.x0, test.y0)  # one pass: view 0's winners and the fold's
    w0 = np.argmax(scores, axis=1)
    w1 = model.winner(test.x1, test.y1, hard=True)
    starved, te, score = fold_indicators(model, test, w0, w1, scores)
    if score >= FOLD_THRESHOLD:
        ring = model.map_shape if model.config.map_periodic else None
        apart = chebyshev(model.map_coords, w0, w1, ring)
        sign = (
            f"views of one z on units >= 3 apart: {np.mean(apart >= 3):.1%}"
            if len(model.map_shape) == 1
            else f"views within one unit: {np.mean(apart <= 1):.1%}, topographic error {te:.3f}"
        )
        hint = (
            'train with --set ordering="crossview"'
            if model.config.ordering == "none"
            else "try another --seed"
        )
        print(
            f"sigmapi train: warning: the map looks folded (fold score {score:.2f} >= "
            f"{FOLD_THRESHOLD:g}: {starved} starved unit{'' if starved == 1 else 's'}, "
            f"{sign}); {hint}",
            file=sys.stderr,
        )


def cmd_evaluate(args: argparse.Namespace) -> int:
    model = load_model(args.model)
    _validate.integer("--n-test", args.n_test, 2, error=UsageError)
    metrics = evaluate(model, n_test=args.n_test).to_dict()
    if args.json:
        print(json.dumps(metrics))
    else:
        for key, value in metrics.items():
            print(f"{key:18s} {value:.4f}" if isinstance(value, float) else f"{key:18s} {value}")
    return 0


def cmd_presets(args: argparse.Namespace) -> int:
    for name in list_presets():
        cfg = load_preset(name)
        print(
            f"{name:16s} map {'x'.join(map(str, cfg.map_shape)):6s} "
            f"x {'x'.join(map(str, cfg.x_shape)):6s} y {'x'.join(map(str, cfg.y_shape)):6s} "
            f"{cfg.iterations:>8d} iterations  {cfg.extra.get('procedure', 'sigmapi')}"
        )
    return 0


def register(sub: argparse._SubParsersAction[LazyParser]) -> None:
    """Add ``train``, ``evaluate`` and ``presets`` to the sub-parsers ``sub``."""
    default = load_preset(DEFAULT_PRESET)
    description = (
        "Train a Sigma-Pi map and write it to a model file (.npz). Without "
        f"--preset this is preset {DEFAULT_PRESET}: the paper's "
        f"{len(default.x_shape)}-D task, {default.iterations:,} iterations by "
        f"sigmapi's procedure ({DEFAULT_PRESET}-authors: the authors' run); try --preset "
        f"tiny-1d for a short run ({load_preset('tiny-1d').iterations:,} iterations)."
    )
    p = sub.add_parser(
        "train",
        help="train a map and write a model file",
        description=textwrap.fill(description, width=78),
        epilog=config_keys_help(),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    add_config_flags(p)
    p.add_argument("--out", required=True, help="model file to write (.npz)")
    p.add_argument(
        "--force", action="store_true", help="overwrite --out if it exists (its mode is kept)"
    )
    p.add_argument(
        "--compress",
        action="store_true",
        help="deflate the model file (smaller, for archives; slower to write and read)",
    )
    p.add_argument(
        "--keep-checkpoints",
        action="store_true",
        help="keep OUT.ckpt/ after the run has finished (default: remove its checkpoints)",
    )
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument(
        "--checkpoint-every",
        type=int,
        metavar="N",
        help="write a checkpoint to OUT.ckpt/ every N iterations (atomic; the 3 newest are "
        "kept while the run lasts)",
    )
    p.add_argument(
        "--resume",
        action="store_true",
        help="continue from the newest good checkpoint of this --out (same command line)",
    )
    declare_path(p, "config", "--config", "input")
    declare_path(p, "out", "--out", "output")
    p.set_defaults(func=cmd_train)

    p = sub.add_parser("evaluate", help="metrics of a model file")
    p.add_argument("model", help="model file written by `sigmapi train`")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.add_argument("--n-test", type=int, default=10_000, help="test set size (default 10000)")
    p.set_defaults(func=cmd_evaluate)

    p = sub.add_parser("presets", help="list the shipped presets")
    p.set_defaults(func=cmd_presets)
