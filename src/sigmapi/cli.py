"""The ``sigmapi`` command line: a thin front that maps flags onto the API's config objects.

Sub-commands: ``train``, ``evaluate``, ``presets``, plus those that other modules register
(``reproduce``, ``figure``, ``reach``): each such module offers ``register(subparsers)``, which
adds its parser and sets ``func`` to a handler ``handler(args) -> int``.

A user mistake (unknown preset, bad value, missing file) prints one line to stderr and exits
with status 2; no traceback.
"""

from __future__ import annotations

import argparse
import importlib
import json
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any, NoReturn

from sigmapi.config import SOMConfig, apply_overrides, list_presets, load_config_file, load_preset
from sigmapi.errors import ConfigError, ModelFileError, NotFittedError

__all__ = ["UsageError", "build_parser", "main", "progress_callback", "resolve_config"]

# modules that add sub-commands of their own (each has ``register(subparsers)``)
PLUGIN_MODULES = ("sigmapi.report", "sigmapi.reach.cli")


class UsageError(Exception):
    """A mistake on the command line, reported as one line with exit status 2."""


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> NoReturn:  # one line, exit 2, as argparse does, no usage dump
        self.exit(2, f"{self.prog}: error: {message}\n")


# ------------------------------------------------------------------------------ helpers


def resolve_config(args: argparse.Namespace) -> SOMConfig:
    """The config of ``--preset`` / ``--config`` / ``--set`` / ``--seed`` / ``--backend``."""
    cfg = load_preset(args.preset) if args.preset else SOMConfig()
    if getattr(args, "config", None):
        cfg = load_config_file(args.config, base=cfg)
    cfg = apply_overrides(cfg, list(getattr(args, "set", None) or []))
    if getattr(args, "seed", None) is not None:
        cfg = cfg.replace(seed=args.seed)
    if getattr(args, "backend", None):
        cfg = cfg.replace(backend=args.backend)
    return cfg


def check_output(path: str | Path, force: bool, what: str = "output file") -> Path:
    """Refuse to overwrite an existing ``path`` without ``--force``; the folder must exist."""
    p = Path(path)
    if p.exists() and not force:
        raise UsageError(f"{what} {str(p)!r} exists; pass --force to overwrite it")
    if p.exists() and p.is_dir():
        raise UsageError(f"{what} {str(p)!r} is a folder; give a file name")
    parent = p.parent if str(p.parent) else Path(".")
    if not parent.is_dir():
        raise UsageError(
            f"folder {str(parent)!r} of {what} {str(p)!r} does not exist; create it first"
        )
    return p


def progress_callback(total: int, desc: str, start: int = 0, disable: bool | None = None) -> Any:
    """A tqdm bar on stderr showing iterations/s and the current sigma; returns (callback, bar)."""
    from tqdm import tqdm

    bar = tqdm(total=total, initial=start, desc=desc, unit="it", unit_scale=True,
               dynamic_ncols=True, file=sys.stderr, disable=disable, mininterval=0.5)  # fmt: skip

    def callback(model: Any) -> None:
        bar.update(model.t_ - bar.n)
        bar.set_postfix(sigma=f"{model.sigma_:.3g}", refresh=False)

    return callback, bar


def _add_config_flags(p: argparse.ArgumentParser) -> None:
    p.add_argument("--preset", default="paper-1d", help="preset name (see `sigmapi presets`)")
    p.add_argument("--config", help="TOML file whose keys override the preset")
    p.add_argument(
        "--set",
        action="append",
        metavar="KEY=VALUE",
        help="override one config key, e.g. --set iterations=50000 (repeatable)",
    )
    p.add_argument("--seed", type=int, help="seed of all random streams (default: the config's)")
    p.add_argument("--backend", choices=["auto", "reference", "fast", "gpu"],
                   help="kernel backend (default: the config's, 'auto')")  # fmt: skip


# ------------------------------------------------------------------------------ commands


def cmd_train(args: argparse.Namespace) -> int:
    from sigmapi.checkpoints import checkpoint_dir, find_resumable, write_checkpoint
    from sigmapi.som import SigmaPiSOM

    cfg = resolve_config(args)
    every = args.checkpoint_every
    if every is not None and every < 1:
        raise UsageError(f"--checkpoint-every must be an int >= 1 (iterations), got {every}")
    # --resume continues the same run, so it may replace that run's --out
    out = check_output(args.out, args.force or args.resume)
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
    if model is None:
        model = SigmaPiSOM(cfg)
        model.partial_fit(0)  # initial weights, iteration 0
    callback, bar = progress_callback(
        cfg.iterations, f"train {args.preset}", start=model.t_, disable=args.quiet or None
    )
    with bar:
        while model.t_ < cfg.iterations:
            step = cfg.iterations - model.t_
            if every is not None:
                step = min(step, every - model.t_ % every)
            model.partial_fit(step, callback=callback)
            if every is not None and model.t_ % every == 0 and model.t_ < cfg.iterations:
                write_checkpoint(model, folder)
    model.save(out)
    print(f"wrote {out} ({model.t_} iterations, backend {model.backend})", file=sys.stderr)
    return 0


def cmd_evaluate(args: argparse.Namespace) -> int:
    from sigmapi.io import load_model
    from sigmapi.metrics import evaluate

    model = load_model(args.model)
    if args.n_test < 2:
        raise UsageError(f"--n-test must be >= 2, got {args.n_test}")
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
            f"{name:12s} map {'x'.join(map(str, cfg.map_shape)):6s} "
            f"x {'x'.join(map(str, cfg.x_shape)):6s} y {'x'.join(map(str, cfg.y_shape)):6s} "
            f"{cfg.iterations:>8d} iterations  {cfg.extra.get('source', '')}"
        )
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="sigmapi", description="Sigma-Pi self-organizing maps (Weber & Wermter 2007)"
    )
    from sigmapi import __version__

    parser.add_argument("--version", action="version", version=f"sigmapi {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)

    p = sub.add_parser("train", help="train a map and write a model file")
    _add_config_flags(p)
    p.add_argument("--out", required=True, help="model file to write (.npz)")
    p.add_argument("--force", action="store_true", help="overwrite --out if it exists")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument(
        "--checkpoint-every",
        type=int,
        metavar="N",
        help="write a checkpoint to OUT.ckpt/ every N iterations (atomic; the 3 newest are kept)",
    )
    p.add_argument(
        "--resume",
        action="store_true",
        help="continue from the newest good checkpoint of this --out (same command line)",
    )
    p.set_defaults(func=cmd_train)

    p = sub.add_parser("evaluate", help="metrics of a model file")
    p.add_argument("model", help="model file written by `sigmapi train`")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.add_argument("--n-test", type=int, default=10_000, help="test set size (default 10000)")
    p.set_defaults(func=cmd_evaluate)

    p = sub.add_parser("presets", help="list the shipped presets")
    p.set_defaults(func=cmd_presets)

    for name in PLUGIN_MODULES:
        try:
            module = importlib.import_module(name)
        except ModuleNotFoundError as exc:
            if exc.name is not None and name.startswith(exc.name):
                continue  # that part of the package is not installed in this build
            raise
        module.register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``sigmapi`` command."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args))
    except (UsageError, ConfigError, ModelFileError, NotFittedError) as exc:
        print(f"sigmapi {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:  # unwritable folder, disk full, ...: the user's environment
        where = f" {exc.filename!r}" if exc.filename else ""
        print(f"sigmapi {args.command}: error: cannot access{where}: {exc.strerror or exc}",
              file=sys.stderr)  # fmt: skip
        return 2
    except KeyboardInterrupt:
        print(f"sigmapi {args.command}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
